#!/bin/sh
# ctest python.pip_install (ADAMESH_TEST_PIP=ON; slow: pip builds the library again): installs the
# package from the source tree into a fresh venv, offline (--no-index, --no-build-isolation:
# Debian's setuptools, wheel, pybind11 and numpy), then meshes a numpy array and a file with it.
#   pip_install.sh PYTHON SOURCE_DIR WORK_DIR
set -eu
py=$1 src=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
"$py" -m venv --system-site-packages "$work/venv"
"$work/venv/bin/pip" install --no-index --no-build-isolation "$src"
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
