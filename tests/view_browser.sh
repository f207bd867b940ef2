#!/usr/bin/env bash
# ctest view_browser: `adamesh view` on a hierarchy of the CT head, driven in headless Chromium
# by viewer/browser-test.mjs (slider moved to two positions, counts checked against
# `adamesh level`, non-blank renderings; screenshots left in SHOT_DIR).
# Exits 77 (ctest: skipped) with a message when node, the npm packages, chromium or the viewer
# bundle are absent.   usage: view_browser.sh ADAMESH SOURCE_DIR SHOT_DIR
set -euo pipefail
bin=$1 src=$2 shots=$3
chromium=${CHROMIUM:-/usr/bin/chromium}
if ! command -v node >/dev/null || [ ! -d "$src/viewer/node_modules/puppeteer-core" ]; then
  echo "SKIP: node or viewer/node_modules/puppeteer-core is absent (scripts/install-deps.sh needs network)"
  exit 77
fi
if [ ! -x "$chromium" ]; then
  echo "SKIP: no Chromium at $chromium (Debian package chromium, installed by scripts/install-deps.sh)"
  exit 77
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
(cd "$src" && "$bin" extract data/ct_headsq/quarter.nhdr --iso 500.5 --quiet --triangles 20000 \
  --hierarchy "$tmp/head.amh" --report "$tmp/head.json")  # relative input name: shown in the page
set +e
"$bin" view "$tmp/head.amh" -o "$tmp/view.html" --report "$tmp/head.json" --quiet
rc=$?
set -e
if [ $rc -eq 3 ]; then
  echo "SKIP: this adamesh was built without the viewer bundle (npm packages absent at build time)"
  exit 77
fi
[ $rc -eq 0 ]
mkdir -p "$shots"
node "$src/viewer/browser-test.mjs" "$bin" "$tmp/head.amh" "$tmp/view.html" "$shots"
