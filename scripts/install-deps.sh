#!/usr/bin/env bash
# Installs the Debian packages adamesh needs, only those that are missing. Idempotent.
#   scripts/install-deps.sh          build + test dependencies
#   scripts/install-deps.sh --bench  also the benchmark peers and plotting tools
#   scripts/install-deps.sh --full   also VTK and CGAL (opt-in peers of `make bench-full`)
#   scripts/install-deps.sh --fuzz   also clang-14 and its libFuzzer runtime (`make fuzz`)
set -euo pipefail

pkgs=(
  build-essential cmake ninja-build pkg-config
  zlib1g-dev            # gzip/zlib encodings in NRRD, MetaImage, NIfTI, VTK XML
  libpugixml-dev        # VTK XML ImageData (.vti) header
  libnifti2-dev         # NIfTI-1/NIfTI-2 header definitions and qform/sform conversion
  libgdcm-dev           # DICOM series input (src/io/dicom.cpp)
  libmuparser-dev       # user expressions  expr:'...'
  libtbb-dev            # oneTBB: parallel stages
  libboost-graph-dev    # Edmonds maximum-cardinality matching (4-8 blocks)
  libmeshoptimizer-dev  # benchmark peer: marching cubes + meshopt_simplify
  nlohmann-json3-dev    # JSON reports (only in .cpp files that write or read JSON)
  libgtest-dev libgmock-dev libbenchmark-dev
  curl xz-utils         # scripts/build-tbb-tsan.sh: oneTBB's Debian source for the TSan job
  python3
  # Python package (python/, docs/PYTHON.md): module, tests, example; `pip install .` offline
  # (in-tree build backend: pip and venv only, nothing downloaded)
  python3-dev python3-pybind11 python3-numpy python3-pytest python3-matplotlib
  python3-pip python3-venv
)
case "${1:-}" in
  --bench) pkgs+=(gnuplot-nox) ;;
  --full)  pkgs+=(gnuplot-nox libvtk9-dev libcgal-dev) ;;
  --fuzz)  pkgs+=(clang-14 libclang-rt-14-dev) ;;
esac

# The web viewer and its tests (viewer/package.json): node + npm (from Debian unless a node is
# already installed, e.g. NodeSource's, which bundles npm), Debian's chromium for the browser test.
command -v node >/dev/null 2>&1 || pkgs+=(nodejs npm)
pkgs+=(chromium)

missing=()
for p in "${pkgs[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -q
  $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# npm packages of the viewer (three, esbuild, puppeteer-core, gltf-validator), pinned by
# viewer/package-lock.json, into viewer/node_modules (git-ignored); only when the lock file is
# newer than the installed tree. Without network this fails with a note and everything else
# still builds: `adamesh view` then exits 3 and the viewer/validator tests skip.
viewer="$(dirname "$0")/../viewer"
stamp="$viewer/node_modules/.package-lock.json"
if command -v npm >/dev/null 2>&1 && { [ ! -f "$stamp" ] || [ "$viewer/package-lock.json" -nt "$stamp" ]; }; then
  echo "install-deps: npm ci in viewer/"
  if ! (cd "$viewer" && npm ci --no-audit --no-fund --loglevel=error >/dev/null); then
    echo "install-deps: npm ci failed (no network?): adamesh view and its tests will be unavailable" >&2
  fi
fi
