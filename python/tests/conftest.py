"""Shared fixtures: the CLI built next to the module, the bundled CT head, temporary files."""
import os
import subprocess

import numpy as np
import pytest

SOURCE_DIR = os.environ.get("ADAMESH_SOURCE_DIR",
                            os.path.dirname(os.path.dirname(os.path.dirname(__file__))))
CLI = os.environ.get("ADAMESH_CLI", "")
HEAD = os.path.join(SOURCE_DIR, "data", "ct_headsq", "quarter.nhdr")


def run_cli(*args, check=True):
    """Runs `adamesh ARGS`; returns (exit code, stdout, stderr)."""
    if not CLI or not os.path.exists(CLI):
        pytest.skip("ADAMESH_CLI is not set (run the tests through ctest)")
    p = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True)
    if check and p.returncode != 0:
        raise AssertionError(f"adamesh {' '.join(map(str, args))}: {p.returncode}\n{p.stderr}")
    return p.returncode, p.stdout, p.stderr


def read_bytes(path):
    with open(path, "rb") as f:
        return f.read()


def sphere_sdf(n=40, radius=0.7, centre=(0.05, -0.03, 0.02)):
    """Signed distance to a sphere sampled on [-1, 1]^3, array[z, y, x]; negative inside."""
    t = np.linspace(-1, 1, n)
    z, y, x = np.meshgrid(t, t, t, indexing="ij")
    cx, cy, cz = centre
    return np.sqrt((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) - radius


def blob(shape=(24, 28, 32)):
    """An asymmetric smooth blob in [0, 200], array[z, y, x] (float64)."""
    nz, ny, nx = shape
    z, y, x = np.meshgrid(np.linspace(-1, 1, nz), np.linspace(-1, 1, ny), np.linspace(-1, 1, nx),
                          indexing="ij")
    r2 = (x / 0.8) ** 2 + ((y - 0.1) / 0.6) ** 2 + ((z + 0.05) / 0.7) ** 2 + 0.2 * x * y
    return np.clip(200.0 * np.exp(-1.5 * r2), 0, 200)
