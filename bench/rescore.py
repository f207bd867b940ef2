#!/usr/bin/env python3
"""Re-scores adamesh's adaptive meshes against the peers' figures stored in a `make bench-full`
results file, without running the peers again (their meshes and RMS do not change with our code).

    bench/rescore.py [--build DIR] [--fit auto,surface] [--skip @512] RESULTS.json > rows.jsonl

For every input and budget where FE + vtkQuadricDecimation has a mesh in RESULTS.json, runs
`adamesh extract INPUT [--iso V] ARGS --triangles N --fit F -o m.ply` for each --fit mode and
`adamesh stats m.ply --field INPUT --json`, and prints one JSON row per (input, budget): the
peer's RMS, ours in the results file ("old") and ours now per fit mode as
[rms, % under 20°, intersecting pairs, triangles]. A summary table (median RMS ratio
ours / vtkQuadric per input kind and budget) goes to stderr at the end.
"""
import argparse, json, os, statistics, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results")
    ap.add_argument("--build", default=os.path.join(ROOT, "build", "release"))
    ap.add_argument("--fit", default="auto,surface")
    ap.add_argument("--skip", default="@512", help="comma-separated substrings of input names to skip")
    a = ap.parse_args()
    exe = os.path.join(a.build, "apps", "adamesh", "adamesh")
    fits = a.fit.split(",")
    skip = [s for s in a.skip.split(",") if s]
    res = json.load(open(a.results))
    tmp = tempfile.mkdtemp()
    rows = []
    for x in res["inputs"]:
        if any(s in x["name"] for s in skip):
            continue
        for m in (x.get("vtk") or {}).get("meshes", []):
            st = m.get("stats") or {}
            if "distance" not in st:
                continue
            n = m["budget"]
            old = [o for o in x["adamesh"] if o.get("budget") == n and "distance" in o.get("stats", {})]
            iso = ["--iso", str(x["iso"])] if x["kind"] != "shape" else []
            row = {"name": x["name"], "kind": x["kind"], "budget": n, "vtk": st["distance"]["rms"],
                   "old": old[0]["stats"]["distance"]["rms"] if old else None}
            for fit in fits:
                path = os.path.join(tmp, "m.ply")
                r = subprocess.run([exe, "extract", x["spec"], *iso, *x["args"], "--triangles", str(n),
                                    "--fit", fit, "-o", path, "--quiet"], capture_output=True, text=True)
                if r.returncode != 0:
                    row[fit] = None
                    continue
                s = json.loads(subprocess.run([exe, "stats", path, "--field", x["spec"], *iso, *x["args"],
                                               "--json"], capture_output=True, text=True, check=True).stdout)
                row[fit] = [s["distance"]["rms"], s["pct_min_angle_below"]["20"],
                            s["self_intersecting_pairs"], s["triangles"]]
            rows.append(row)
            print(json.dumps(row), flush=True)

    def summary(sel, key):
        r = [(x[key] if key == "old" else x[key][0]) / x["vtk"] for x in sel
             if (x[key] if key == "old" else x[key]) is not None]
        if not r:
            return "–"
        return f"{statistics.median(r):.2f} ({sum(q <= 1 for q in r)} of {len(r)} ≤ 1, worst {max(r):.2f})"

    keys = ["old"] + fits
    print("| inputs | budget | " + " | ".join(keys) + " |", file=sys.stderr)
    print("|---" * (2 + len(keys)) + "|", file=sys.stderr)
    for kind in ("shape", "dataset"):
        for n in sorted({x["budget"] for x in rows}):
            sel = [x for x in rows if (x["kind"] == "shape") == (kind == "shape") and x["budget"] == n]
            if sel:
                name = "shapes" if kind == "shape" else "scans"
                print(f"| {name} | {n} | " + " | ".join(summary(sel, k) for k in keys) + " |", file=sys.stderr)
    print("| all | all | " + " | ".join(summary(rows, k) for k in keys) + " |", file=sys.stderr)


if __name__ == "__main__":
    main()
