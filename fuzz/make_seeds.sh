#!/usr/bin/env bash
# Regenerates the seed corpora in fuzz/corpus/<reader>/ (committed; every file is small):
# volume seeds are the robustness test's valid files (tests/io_volume_robustness_test.cpp),
# mesh and .amh seeds are tiny outputs of the CLI. Needs the test build (make test).
#   fuzz/make_seeds.sh [BUILD_DIR]     (default build/test)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/test}
corpus=fuzz/corpus
cli=$build/apps/adamesh/adamesh
ADAMESH_FUZZ_SEEDS=$PWD/$corpus "$build/tests/dicom_test" \
  --gtest_filter=Dicom.SmallSeriesInEverySyntaxReadBack >/dev/null
ADAMESH_FUZZ_SEEDS=$PWD/$corpus "$build/tests/io_volume_test" \
  --gtest_filter=VolumeRobustness.SeedsAreValid >/dev/null
for f in ply obj off stl amh; do mkdir -p "$corpus/$f"; done
"$cli" mc shape:sphere --res 5 --quiet -o "$corpus/ply/seed_binary.ply"
"$cli" mc shape:torus --res 6 --quiet --ascii -o "$corpus/ply/seed_ascii.ply"
"$cli" mc shape:sphere --res 5 --quiet -o "$corpus/obj/seed.obj"
"$cli" mc shape:sphere --res 5 --quiet -o "$corpus/off/seed.off"
"$cli" mc shape:sphere --res 5 --quiet -o "$corpus/stl/seed_binary.stl"
printf 'solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n' \
  > "$corpus/stl/seed_ascii.stl"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3\nf 1/1/1 -1 -2 -3\n' \
  > "$corpus/obj/seed_normals.obj"
"$cli" extract shape:sphere --res 12 --rmax 0.6 --levels 1 --quiet --hierarchy "$corpus/amh/seed.amh"
"$cli" extract shape:sphere --res 8 --levels 2 --quiet --hierarchy "$corpus/amh/sphere_levels2.amh"
"$cli" extract 'expr:x^2+y^2-0.3' --bounds -1,-1,-1,1,1,1 --res 8 --levels 2 --quiet \
  --hierarchy "$corpus/amh/cylinder_border.amh"  # open: border vertices
"$cli" extract shape:sphere --res 10 --triangles 200 --quiet --hierarchy "$corpus/amh/sphere_adaptive.amh"
# The same sphere without the anchor array (header flags 0): the other layout the reader accepts.
python3 - "$corpus/amh/sphere_levels2.amh" "$corpus/amh/sphere_no_anchors.amh" <<'PY'
import struct, sys
b = open(sys.argv[1], 'rb').read()
v0 = struct.unpack_from('<Q', b, 16)[0]
p = 104 + 25 * v0  # header, positions, border flags; then 4-byte anchors
out = bytearray(b[:p] + b[p + 4 * v0:-8])
struct.pack_into('<I', out, 12, 0)
h = 1469598103934665603
for c in out:
    h = ((h ^ c) * 1099511628211) & 0xffffffffffffffff
open(sys.argv[2], 'wb').write(out + struct.pack('<Q', h))
PY
du -sh "$corpus"
