#!/usr/bin/env python3
"""Stage times of two adamesh binaries on the shared scans, alternating runs, best of two.

usage: bench/compare_stages.py BEFORE AFTER [--budgets default,20000] [--threads 2]

Prints one Markdown row per input and budget: improve_base, improve and the sum of the report's
stage timings without read and write (seconds, before → after) and the speed-up. The inputs are
read from ../shared/data (skipped with a message when absent). Python standard library only.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATA = os.path.normpath(os.path.join(ROOT, "..", "shared", "data"))
INPUTS = [
    ("ct_headsq@500.5", ["ct_headsq/quarter.nhdr", "--iso", "500.5"]),
    ("ct_headsq@1150.5", ["ct_headsq/quarter.nhdr", "--iso", "1150.5"]),
    ("mri_headmr@20.5", ["mri_headmr/HeadMRVolume.mhd", "--iso", "20.5"]),
    ("mri_avg152T1@60.5", ["mri_avg152T1/avg152T1_RL_nifti.nii.gz", "--iso", "60.5"]),
    ("ct_lidc2_chest@200.5", ["ct_lidc2_chest/LIDC2.nhdr", "--iso", "200.5"]),
    ("ct_lidc2_chest@100.5", ["ct_lidc2_chest/LIDC2.nhdr", "--iso", "100.5"]),
    ("gyroid@128", ["shape:gyroid", "--res", "128"]),
]


def run(binary, args, budget, threads, tmp):
    report = os.path.join(tmp, "r.json")
    cmd = [binary, "extract"] + args + ["-o", os.path.join(tmp, "m.ply"), "--report", report,
                                        "--quiet", "--threads", threads]
    if budget != "default":
        cmd += ["--triangles", budget]
    subprocess.run(cmd, check=True)
    t = json.load(open(report))["timings_s"]
    return (t.get("improve_base", 0.0), t.get("improve", 0.0),
            sum(v for k, v in t.items() if k not in ("read", "write")))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("--budgets", default="default,20000")
    ap.add_argument("--threads", default="2")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for name, args in INPUTS:
            if not args[0].startswith("shape:"):
                path = os.path.join(DATA, args[0])
                if not os.path.exists(path):
                    print(f"skipped {name}: {path} not found", file=sys.stderr)
                    continue
                args = [path] + args[1:]
            for budget in a.budgets.split(","):
                runs = {"before": [], "after": []}
                for _ in range(2):
                    for which, binary in (("before", a.before), ("after", a.after)):
                        runs[which].append(run(binary, args, budget, a.threads, tmp))
                b = [min(r[i] for r in runs["before"]) for i in range(3)]
                n = [min(r[i] for r in runs["after"]) for i in range(3)]
                print(f"| {name} | {budget} | {b[0]:.2f} → {n[0]:.2f} | {b[1]:.2f} → {n[1]:.2f} | "
                      f"{b[2]:.2f} → {n[2]:.2f} | {b[2] / n[2]:.2f}× |", flush=True)


if __name__ == "__main__":
    main()
