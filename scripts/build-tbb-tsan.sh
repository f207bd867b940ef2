#!/usr/bin/env bash
# Builds oneTBB with ThreadSanitizer for the TSan job (scripts/sanitize.sh; docs/FUZZING.md).
#
# Why: Debian's libtbb is not instrumented, so TSan does not see the task scheduler's
# synchronisation (work stealing, the join of parallel_for) and reports races between a task's
# writes and the caller's reads after the join — false positives that would hide real ones. The
# fix oneTBB documents is to build the library itself with TBB_SANITIZE=thread.
#
# What: the Debian source of the oneTBB version the system has (bookworm: 2021.8.0, the upstream
# tarball of the Debian package, checked against the SHA-256 of its signed .dsc), downloaded
# from deb.debian.org into build/tbb-tsan/ (never committed), configured with TBB_SANITIZE=thread,
# the `tbb` library built (no tbbmalloc, no tests, no examples), installed into build/tbb-tsan/install.
# Nothing is downloaded or built again once the install exists. Prints the install prefix.
#   scripts/build-tbb-tsan.sh [JOBS]
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${1:-2}
version=2021.8.0
sha256=7e9111b8bb59c8800bf6d0b06afe7b0891937443d2dae1ee1101c8e2ede6a7ef
url=http://deb.debian.org/debian/pool/main/o/onetbb/onetbb_${version}.orig.tar.xz
root=$PWD/build/tbb-tsan
prefix=$root/install
if [ -f "$prefix/lib/cmake/TBB/TBBConfig.cmake" ]; then
  echo "$prefix"
  exit 0
fi
mkdir -p "$root"
tarball=$root/onetbb_${version}.orig.tar.xz
if ! echo "$sha256  $tarball" | sha256sum -c --status 2>/dev/null; then
  echo "build-tbb-tsan: downloading $url" >&2
  curl -fsSL --retry 3 -o "$tarball.part" "$url"
  echo "$sha256  $tarball.part" | sha256sum -c --status ||
    { echo "build-tbb-tsan: $tarball: SHA-256 differs from the Debian .dsc's" >&2; exit 1; }
  mv "$tarball.part" "$tarball"
fi
rm -rf "$root/src" "$root/build"
mkdir -p "$root/src"
tar -xf "$tarball" -C "$root/src" --strip-components=1
# The same compiler as the tsan preset (g++); -O1 keeps the scheduler's stacks readable.
cmake -S "$root/src" -B "$root/build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DTBB_SANITIZE=thread -DTBB_TEST=OFF \
  -DTBB_STRICT=OFF -DTBB_EXAMPLES=OFF -DTBBMALLOC_BUILD=OFF -DTBB_ENABLE_IPO=OFF \
  -DCMAKE_INSTALL_PREFIX="$prefix" -DCMAKE_INSTALL_LIBDIR=lib >&2
cmake --build "$root/build" -j "$jobs" >&2
cmake --install "$root/build" >&2
echo "$prefix"
