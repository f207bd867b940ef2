#!/usr/bin/env bash
# The benchmark suite: `make bench` (default), `make bench-quick` (--quick, under two minutes),
# `make bench-full` (--full: also 512³ shapes and the VTK / CGAL peers).
#   bench/run.sh [--quick|--full] [--build DIR] [--only NAME,NAME] [--repeat N] [--no-micro]
# Writes bench/results/<date>.json and regenerates docs/BENCHMARKS.md (+ docs/img/bench_*.svg).
# Expects a build with -DADAMESH_BUILD_BENCH=ON (default: build/release, as `make bench` makes).
set -euo pipefail
cd "$(dirname "$0")/.."
mode=default
args=()
for a in "$@"; do
  case "$a" in
    --quick) mode=quick ;;
    --full) mode=full ;;
    *) args+=("$a") ;;
  esac
done
# Debian's python3 (standard library only), not whatever python3 comes first on PATH.
py=/usr/bin/python3
[ -x "$py" ] || py=python3
exec "$py" bench/bench.py --mode "$mode" "${args[@]}"
