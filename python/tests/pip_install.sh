#!/bin/sh
# ctest python.pip_install (label slow): `pip install .` as a user types it — build isolation on
# (no --no-build-isolation), nothing from an index (--no-index, PIP_NO_INDEX=1) and, where user
# namespaces are allowed, no network at all (unshare -rn) — into a fresh venv that sees Debian's
# numpy. pyproject.toml's in-tree backend builds the module with CMake and writes the wheel; then
# the installed package meshes a numpy array and a file, and the backend's sdist is checked.
#   pip_install.sh PYTHON SOURCE_DIR WORK_DIR
# The backend's CMake folder is kept in WORK_DIR-cmake (ADAMESH_BUILD_DIR): the first run builds
# the library (Release, its own build, not the test build's objects), later runs are incremental.
set -eu
py=$1 src=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
"$py" -m venv --system-site-packages "$work/venv"

offline=""
if command -v unshare >/dev/null 2>&1 && unshare -rn true 2>/dev/null; then
  offline="unshare -rn"  # a network namespace with no interface but lo
  echo "pip_install: running pip without network (unshare -rn)"
else
  echo "pip_install: user namespaces unavailable: PIP_NO_INDEX=1 and --no-index only"
fi
export PIP_NO_INDEX=1 PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_ROOT_USER_ACTION=ignore
export PIP_NO_CACHE_DIR=1
export ADAMESH_BUILD_DIR="$work-cmake"
export CMAKE_BUILD_PARALLEL_LEVEL="${CMAKE_BUILD_PARALLEL_LEVEL:-2}"
$offline "$work/venv/bin/pip" install --no-index "$src"

cd "$work"  # not the source tree: the installed package is imported
"$work/venv/bin/python" - "$src" <<'PY'
import sys
import numpy as np
import adamesh
assert adamesh.__file__.startswith(sys.prefix), adamesh.__file__
z, y, x = np.mgrid[-1:1:40j, -1:1:40j, -1:1:40j]
ball = adamesh.Volume(np.sqrt(x**2 + y**2 + z**2) - 0.7, order="zyx", spacing=2 / 39,
                      inside="negative")
r = adamesh.extract(ball, triangles=2000)
assert 0 < len(r.faces) <= 2000 and adamesh.stats(r.mesh)["euler"] == 2
head = adamesh.extract(sys.argv[1] + "/data/ct_headsq/quarter.nhdr", 500.5, triangles=5000)
print("pip-installed adamesh:", adamesh.__file__, len(r.faces), len(head.faces))
PY
# pip's own view of the installed distribution: metadata and the RECORD it wrote.
"$work/venv/bin/pip" show -f adamesh | grep -E "^(Name|Version|Requires): |_adamesh.*\.so|RECORD"

# The sdist: every tracked source, pyproject.toml and PKG-INFO at the top.
"$py" - "$src" "$work/sdist" <<'PY'
import sys, tarfile
sys.path.insert(0, sys.argv[1] + "/python/build_backend")
import adamesh_build
name = adamesh_build.build_sdist(sys.argv[2])
names = tarfile.open(f"{sys.argv[2]}/{name}").getnames()
top = name[:-len(".tar.gz")]
for want in ("pyproject.toml", "PKG-INFO", "CMakeLists.txt", "python/build_backend/adamesh_build.py",
             "python/src/module.cpp", "src/pipeline/extract.cpp"):
    assert f"{top}/{want}" in names, want
assert not any("/build/" in n for n in names)
print("sdist:", name, len(names), "files")
PY
