#!/bin/sh
# Regenerates docs/MC_TABLE.md: the reference marching cubes (`adamesh mc`) on every dataset of
# ../shared/data at each suggested iso-value and at the plain integer value for integer data.
# The numbers come from tests/mc_test.cpp (MarchingCubesData.*), which also asserts that every
# mesh is manifold, oriented and free of degenerate or duplicate triangles.
#   usage: scripts/mc_table.sh [BUILD_DIR] [THREADS]   (default: build/test, all threads)
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build/test}
[ -f "$build/CMakeCache.txt" ] || (cd "$root" && cmake --preset test >/dev/null)
cmake --build "$build" --target mc_test >/dev/null
table=$(mktemp)
trap 'rm -f "$table"' EXIT
ADAMESH_MC_TABLE="$table" "$build/tests/mc_test" --gtest_filter='MarchingCubesData.*' >/dev/null
out="$root/docs/MC_TABLE.md"
{
  cat <<'HEAD'
# Reference marching cubes on the shared datasets

`adamesh mc` (the surfel complex of ALGORITHM.md 2.2 triangulated per polygon) on every dataset of
`../shared/data/manifest.json`, at each suggested iso-value and — for integer data — at the plain
integer value (samples equal to the iso-value count as inside; node parameters are clamped to
[1/1024, 1 − 1/1024]). Every mesh has 0 non-manifold edges and vertices, 0 degenerate and
0 duplicate triangles and a consistent orientation, and its χ equals the surfel complex's
(asserted by `tests/mc_test.cpp`, `MarchingCubesData.*`). χ, components and boundary loops are
those of `adamesh stats` (include/adamesh/metrics.h).

Time: surfel complex + triangulation, best of three runs in one process, on the machine that
generated the table (volume loading excluded); M voxels/s = (nx−1)(ny−1)(nz−1) / time.
The last column is the manifest's scikit-image (Lewiner, MC33-style) reference for the same
iso-value: a regression reference, not ground truth. Counts differ where the two methods resolve
ambiguous faces and cell interiors differently (Lewiner models interior tunnels; we do not, see
docs/TOPOLOGY.md), which changes χ and the number of components of noisy data noticeably.

Regenerate with `scripts/mc_table.sh [BUILD_DIR]`.

HEAD
  cat "$table"
  printf '\nGenerated %s on %s (%s hardware threads).\n' "$(date -u +%Y-%m-%d)" "$(uname -m)" "$(nproc)"
} >"$out"
echo "wrote $out"
