#!/usr/bin/env bash
# `make demo`: runs adamesh on the bundled CT head (data/ct_headsq, BSD-3, see its LICENSE.md).
set -euo pipefail
bin=${1:-build/release/apps/adamesh/adamesh}
input=data/ct_headsq/quarter.nhdr
out=out/demo
mkdir -p "$out"
echo "== adamesh info $input"
"$bin" info "$input"
