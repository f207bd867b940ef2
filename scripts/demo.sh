#!/usr/bin/env bash
# `make demo`: the whole pipeline on the bundled CT head (data/ct_headsq, BSD-3, see LICENSE.md):
# marching cubes for reference, then the base mesh M0, the refinement hierarchy (.amh), the default
# adaptive mesh, uniform levels and triangle-budget cuts taken from the hierarchy without the volume,
# every mesh scored against the volume by `adamesh stats`, a table of the results, and the
# hierarchy in a web page (out/demo/view.html, `adamesh view`).
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
echo "== adamesh extract: base mesh M0, hierarchy, adaptive mesh (default: 0.25 voxel, at most marching cubes' triangle count)"
"$bin" extract "$input" --iso "$iso" -o "$out/head.ply" --base "$out/head_base.ply" \
  --hierarchy "$out/head.amh" --report "$out/head_report.json"
echo
echo "== meshes cut from the hierarchy (adamesh level, no volume needed)"
written=("$out/head_mc.ply" "$out/head_base.ply" "$out/head.ply" "$out/head.amh" "$out/head_report.json")
cuts=()
for k in 2 4; do
  "$bin" level "$out/head.amh" --level "$k" -o "$out/head_level$k.ply"
  cuts+=("level $k=$out/head_level$k.ply")
done
for n in 10000 30000; do
  "$bin" level "$out/head.amh" --triangles "$n" --improve -o "$out/head_${n}.ply"
  cuts+=("budget $n=$out/head_${n}.ply")
done
echo
echo "== scoring every mesh against the volume (adamesh stats --field $input --iso $iso)"
table=()
score() {  # LABEL MESH
  local json="$out/stats_$(basename "${2%.*}").json"
  "$bin" stats "$2" --field "$input" --iso "$iso" --json >"$json"
  table+=("$1=$json")
}
score "marching cubes" "$out/head_mc.ply"
score "M0 (base mesh)" "$out/head_base.ply"
for c in "${cuts[@]}"; do
  score "${c%%=*}" "${c#*=}"
  written+=("${c#*=}")
done
score "adaptive (default)" "$out/head.ply"
echo
python3 scripts/demo_table.py "${table[@]}"
echo
echo "distances in world units (mm); rms/diag relative to the bounding-box diagonal; eps_e/eps_n:"
echo "edge and normal deviation (docs/METRICS.md); level k: uniform level of the hierarchy where"
echo "the adaptive refinement reached it; budget N: the longest prefix of head.amh with at most N"
echo "triangles (largest errors split first), shape-improved without the volume (level --improve,"
echo "docs/QUALITY.md)."
echo
echo "== adamesh view: the hierarchy in one self-contained web page (level slider, no volume needed)"
if "$bin" view "$out/head.amh" -o "$out/view.html" --report "$out/head_report.json"; then
  written+=("$out/view.html")
  view_note="open $out/view.html in a browser (xdg-open $out/view.html, or file://$(realpath "$out/view.html"))"
else
  view_note="adamesh view is unavailable in this build (see the message above)"
fi
echo
echo "wrote:"
printf '  %s\n' "${written[@]}" "$out"/stats_*.json
echo
echo "$view_note"
