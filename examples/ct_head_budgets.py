#!/usr/bin/env python3
"""Meshes the bundled CT head (data/ct_headsq/quarter.nhdr, skin at iso 500.5) at three triangle
budgets and saves a PNG of the three meshes side by side.

    PYTHONPATH=build/release/python python3 examples/ct_head_budgets.py -o head.png
    (or after `pip install --no-build-isolation .`: python3 examples/ct_head_budgets.py)
"""
import argparse
import os
import time

import matplotlib

matplotlib.use(os.environ.get("MPLBACKEND", "Agg"))
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

import adamesh  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
HEAD = os.path.join(HERE, "..", "data", "ct_headsq", "quarter.nhdr")


def shaded(ax, vertices, faces, title):
    """Flat-shaded triangles (headlight from the viewer's side)."""
    tri = vertices[faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    light = np.array([-0.4, -0.8, 0.45])
    light /= np.linalg.norm(light)
    shade = 0.25 + 0.75 * np.clip(n @ light, 0, 1)
    colors = np.column_stack([0.95 * shade, 0.78 * shade, 0.65 * shade, np.ones_like(shade)])
    ax.add_collection3d(Poly3DCollection(tri, facecolors=colors, edgecolors="none"))
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    c, r = (lo + hi) / 2, (hi - lo).max() / 2
    ax.set_xlim(c[0] - r, c[0] + r)
    ax.set_ylim(c[1] - r, c[1] + r)
    ax.set_zlim(c[2] - r, c[2] + r)
    ax.view_init(elev=5, azim=-80)
    ax.invert_zaxis()  # slice 0 of the scan is the top of the head
    ax.set_axis_off()
    ax.set_title(title, fontsize=10)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-o", "--output", default="ct_head_budgets.png")
    p.add_argument("--budgets", default="2000,10000,40000")
    args = p.parse_args()

    volume = adamesh.load(HEAD)  # samples shared with the library: volume.array is a numpy view
    print(f"{HEAD}: {volume.shape} (z, y, x) {volume.dtype}, spacing {volume.spacing}")
    budgets = [int(b) for b in args.budgets.split(",")]
    fig = plt.figure(figsize=(4 * len(budgets), 4.4), dpi=100)
    for k, n in enumerate(budgets):
        t0 = time.perf_counter()
        result = adamesh.extract(volume, 500.5, triangles=n)
        seconds = time.perf_counter() - t0
        worst = result.report["refine"]["improve"]["min_angle_after"]
        print(f"budget {n}: {len(result.faces)} triangles, {len(result.vertices)} vertices, "
              f"{seconds:.2f} s, smallest angle {worst:.1f} deg")
        ax = fig.add_subplot(1, len(budgets), k + 1, projection="3d")
        shaded(ax, result.vertices, result.faces, f"--triangles {n}: {len(result.faces)}")
    fig.subplots_adjust(left=0, right=1, bottom=0, top=0.93, wspace=0)
    fig.savefig(args.output)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
