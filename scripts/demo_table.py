#!/usr/bin/env python3
"""Print the `make demo` table from `adamesh stats --json` files.

usage: demo_table.py LABEL=STATS.json [LABEL=STATS.json ...]

One row per mesh: triangles, topology (chi / components / boundary loops), RMS and maximum distance
to the iso-surface (world units and relative to the bounding-box diagonal), edge and normal
deviation, minimum-angle statistics and the share of triangles under 20 degrees.
"""
import json
import sys


def row(label, s):
    d = s["distance"]
    ma = s["min_angle_deg"]
    topo = f'{s["euler"]}/{s["components"]}/{s["boundary_loops"]}'
    return [label, f'{s["triangles"]:,}', topo,
            f'{d["rms"]:.3g}', f'{d["max"]:.3g}', f'{d["rms_rel"]:.2e}',
            f'{s["eps_e"]:.2e}', f'{s["eps_n"]:.3f}',
            f'{ma["median"]:.1f}', f'{ma["p5"]:.1f}', f'{s["pct_min_angle_below"]["20"]:.2f}']


def main(argv):
    if len(argv) < 2:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    head = ["mesh", "triangles", "chi/comp/loops", "rms", "max", "rms/diag", "eps_e", "eps_n",
            "min-angle median", "p5", "% < 20 deg"]
    rows = []
    for arg in argv[1:]:
        label, _, path = arg.partition("=")
        try:
            with open(path) as f:
                rows.append(row(label, json.load(f)))
        except (OSError, ValueError, KeyError) as e:
            print(f"demo_table: {path}: {e}", file=sys.stderr)
            return 1
    widths = [max(len(r[i]) for r in rows + [head]) for i in range(len(head))]
    fmt = lambda r: "  ".join(c.ljust(w) if i == 0 else c.rjust(w)
                              for i, (c, w) in enumerate(zip(r, widths)))
    print(fmt(head))
    print("  ".join("-" * w for w in widths))
    for r in rows:
        print(fmt(r))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
