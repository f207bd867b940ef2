#!/usr/bin/env bash
# `make demo`: the whole pipeline on the bundled CT head (data/ct_headsq, BSD-3, see LICENSE.md).
set -euo pipefail
bin=${1:-build/release/apps/adamesh/adamesh}
input=data/ct_headsq/quarter.nhdr
iso=500.5
out=out/demo
mkdir -p "$out"
echo "== adamesh info $input"
"$bin" info "$input"
echo
echo "== marching cubes (reference) at iso $iso"
"$bin" mc "$input" --iso "$iso" -o "$out/head_mc.ply"
echo
echo "== base mesh (disk covering -> Voronoi covering -> dual)"
"$bin" extract "$input" --iso "$iso" --base "$out/head_base.ply" --report "$out/head_report.json"
echo
echo "== base mesh quality and error against the volume"
"$bin" stats "$out/head_base.ply" --field "$input" --iso "$iso"
echo
echo "wrote: $out/head_mc.ply $out/head_base.ply $out/head_report.json"
