#!/usr/bin/env bash
# ctest gltf_validator: the Khronos glTF validator (npm gltf-validator, viewer/package.json) on
# what `adamesh extract` writes: .glb and .gltf+.bin, with and without --compress.
# Exits 77 (ctest: skipped) with a message when node or the npm packages are absent.
# usage: gltf_validator.sh ADAMESH SOURCE_DIR
set -euo pipefail
bin=$1 src=$2
validator="$src/viewer/node_modules/gltf-validator"
if ! command -v node >/dev/null || [ ! -d "$validator" ]; then
  echo "SKIP: node or $validator is absent (run scripts/install-deps.sh with network access)"
  exit 77
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bin" extract "$src/data/ct_headsq/quarter.nhdr" --iso 500.5 --quiet --triangles 20000 \
  -o "$tmp/head.glb" --base "$tmp/base.gltf"
"$bin" extract "$src/data/ct_headsq/quarter.nhdr" --iso 500.5 --quiet --triangles 20000 \
  -o "$tmp/head_c.glb" --base "$tmp/base_c.gltf" --compress
"$bin" extract shape:wavy_sheet --res 32 --quiet --triangles 2000 -o "$tmp/sheet.glb"  # open surface
node "$src/viewer/validate-gltf.mjs" "$tmp/head.glb" "$tmp/base.gltf" "$tmp/head_c.glb" \
  "$tmp/base_c.gltf" "$tmp/sheet.glb"
