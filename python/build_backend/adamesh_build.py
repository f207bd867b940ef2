"""In-tree PEP 517 build backend of the `adamesh` Python package (pyproject.toml: backend-path).

`pip install .` needs nothing from a package index: no setuptools, wheel or pybind11 download
(build-system.requires is empty), so a plain `pip install .` works offline with the Debian
packages of scripts/install-deps.sh (cmake, ninja-build, python3-dev, python3-pybind11,
python3-numpy). The backend

* configures the repository with CMake (Release, ADAMESH_BUILD_PYTHON=ON, tests and install rules
  off; pybind11 found through its CMake package, /usr/lib/cmake/pybind11 on Debian) and builds the
  one target `_adamesh`, the compiled module, for the interpreter running pip;
* writes the wheel itself (a zip archive with adamesh/ and adamesh-VERSION.dist-info/ holding
  METADATA, WHEEL and RECORD, as the binary distribution format specification says);
* writes an sdist (the git-tracked files, or the tree without build outputs, plus PKG-INFO).

Settings (`pip install . -C build-dir=PATH`, or the environment): `build-dir` /
ADAMESH_BUILD_DIR keeps the CMake build folder there (incremental rebuilds; default: a temporary
folder removed afterwards); `jobs` / CMAKE_BUILD_PARALLEL_LEVEL (default: all cores).
"""
from __future__ import annotations

import base64
import hashlib
import io
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import tarfile
import tempfile
import time
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGE_DIR = ROOT / "python" / "adamesh"
PACKAGE_FILES = ("__init__.py", "_adamesh.pyi", "py.typed")
# Build outputs and local folders never shipped in an sdist made without git.
SDIST_SKIP = {"build", "out", ".git", "node_modules", "__pycache__", "dist"}


# ------------------------------------------------------------------------------ metadata

def _project() -> dict:
    try:
        import tomllib  # Python 3.11+
    except ModuleNotFoundError:  # pragma: no cover - older interpreters
        try:
            import tomli as tomllib  # type: ignore[no-redef]
        except ModuleNotFoundError as e:
            raise RuntimeError("adamesh's build backend reads pyproject.toml with tomllib "
                               "(Python 3.11+) or the tomli package") from e
    with open(ROOT / "pyproject.toml", "rb") as f:
        return tomllib.load(f)["project"]


def _dist_name(project: dict) -> str:
    return re.sub(r"[-_.]+", "_", project["name"]).lower()


def _metadata(project: dict) -> str:
    """Core metadata 2.1 (METADATA in the wheel, PKG-INFO in the sdist)."""
    lines = ["Metadata-Version: 2.1", f"Name: {project['name']}",
             f"Version: {project['version']}"]
    if "description" in project:
        lines.append(f"Summary: {project['description']}")
    if "requires-python" in project:
        lines.append(f"Requires-Python: {project['requires-python']}")
    for req in project.get("dependencies", []):
        lines.append(f"Requires-Dist: {req}")
    for extra, reqs in project.get("optional-dependencies", {}).items():
        lines.append(f"Provides-Extra: {extra}")
        for req in reqs:
            lines.append(f'Requires-Dist: {req}; extra == "{extra}"')
    body = ""
    readme = project.get("readme")
    if isinstance(readme, str) and (ROOT / readme).is_file():
        lines.append("Description-Content-Type: text/markdown")
        body = (ROOT / readme).read_text(encoding="utf-8")
    return "\n".join(lines) + "\n\n" + body


def _wheel_tag() -> str:
    """cpXY-cpXY[d]-PLATFORM of the running interpreter: the compiled module is built for it."""
    if sys.implementation.name != "cpython":
        raise RuntimeError("adamesh's compiled module is built for CPython only")
    py = f"cp{sys.version_info[0]}{sys.version_info[1]}"
    abi = py + ("d" if hasattr(sys, "gettotalrefcount") else "")
    platform = re.sub(r"[^A-Za-z0-9]", "_", sysconfig.get_platform())
    return f"{py}-{abi}-{platform}"


def _write_dist_info(directory: Path, project: dict, tag: str) -> str:
    name = f"{_dist_name(project)}-{project['version']}.dist-info"
    info = directory / name
    info.mkdir(parents=True, exist_ok=True)
    (info / "METADATA").write_text(_metadata(project), encoding="utf-8")
    (info / "WHEEL").write_text(
        "Wheel-Version: 1.0\nGenerator: adamesh_build (python/build_backend)\n"
        f"Root-Is-Purelib: false\nTag: {tag}\n", encoding="utf-8")
    (info / "top_level.txt").write_text("adamesh\n", encoding="utf-8")
    return name


# ------------------------------------------------------------------------------ building

def _setting(config_settings: dict | None, key: str, env: str) -> str | None:
    value = (config_settings or {}).get(key)
    if isinstance(value, list):
        value = value[-1] if value else None
    return value or os.environ.get(env) or None


def _build_module(build_dir: Path, out_dir: Path, jobs: str | None) -> Path:
    """Configures and builds the _adamesh target; the package lands in out_dir/adamesh."""
    generator = ["-G", "Ninja"] if shutil.which("ninja") else []
    if (build_dir / "CMakeCache.txt").exists():
        generator = []  # an existing build folder keeps its generator
    cmd = ["cmake", "-S", str(ROOT), "-B", str(build_dir), *generator,
           "-DCMAKE_BUILD_TYPE=Release", "-DADAMESH_BUILD_TESTS=OFF", "-DADAMESH_INSTALL=OFF",
           "-DADAMESH_BUILD_PYTHON=ON", f"-DPython3_EXECUTABLE={sys.executable}",
           f"-DADAMESH_PYTHON_OUTPUT_DIR={out_dir}"]
    print("adamesh build backend:", " ".join(cmd), file=sys.stderr, flush=True)
    subprocess.check_call(cmd, stdout=sys.stderr)
    build = ["cmake", "--build", str(build_dir), "--target", "_adamesh"]
    build += ["-j", jobs or str(os.cpu_count() or 2)]
    subprocess.check_call(build, stdout=sys.stderr)
    suffix = sysconfig.get_config_var("EXT_SUFFIX") or ".so"
    module = out_dir / "adamesh" / f"_adamesh{suffix}"
    if not module.is_file():
        found = sorted((out_dir / "adamesh").glob("_adamesh*"))
        raise RuntimeError(f"the build did not produce {module.name} for {sys.executable} "
                           f"(found: {[p.name for p in found]}); is python3-dev installed "
                           "for this interpreter?")
    return module


def _record_line(arcname: str, data: bytes) -> str:
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"{arcname},sha256={digest},{len(data)}"


def _zip_info(arcname: str, mode: int) -> zipfile.ZipInfo:
    # Fixed timestamps (SOURCE_DATE_EPOCH when set): the same sources give the same archive.
    epoch = max(int(os.environ.get("SOURCE_DATE_EPOCH", "315532800")), 315532800)
    zi = zipfile.ZipInfo(arcname, date_time=time.gmtime(epoch)[:6])
    zi.external_attr = (mode & 0xFFFF) << 16
    zi.compress_type = zipfile.ZIP_DEFLATED
    return zi


# ------------------------------------------------------------------------------ PEP 517 hooks

def get_requires_for_build_wheel(config_settings=None):
    return []


def get_requires_for_build_sdist(config_settings=None):
    return []


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):
    return _write_dist_info(Path(metadata_directory), _project(), _wheel_tag())


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    project = _project()
    tag = _wheel_tag()
    dist = f"{_dist_name(project)}-{project['version']}"
    wheel_path = Path(wheel_directory) / f"{dist}-{tag}.whl"
    jobs = _setting(config_settings, "jobs", "CMAKE_BUILD_PARALLEL_LEVEL")
    keep = _setting(config_settings, "build-dir", "ADAMESH_BUILD_DIR")
    with tempfile.TemporaryDirectory(prefix="adamesh-wheel-") as tmp:
        build_dir = Path(keep).resolve() if keep else Path(tmp) / "cmake"
        out_dir = Path(tmp) / "package"
        module = _build_module(build_dir, out_dir, jobs)
        files: list[tuple[str, bytes, int]] = []
        for name in PACKAGE_FILES:  # from the source tree: what the user sees is what is shipped
            files.append((f"adamesh/{name}", (PACKAGE_DIR / name).read_bytes(), 0o644))
        files.append((f"adamesh/{module.name}", module.read_bytes(), 0o755))
        info_dir = Path(tmp) / "info"
        info = _write_dist_info(info_dir, project, tag)
        for p in sorted((info_dir / info).iterdir()):
            files.append((f"{info}/{p.name}", p.read_bytes(), 0o644))
        record = [_record_line(arc, data) for arc, data, _ in files]
        record.append(f"{info}/RECORD,,")
        files.append((f"{info}/RECORD", ("\n".join(record) + "\n").encode(), 0o644))
        tmp_wheel = Path(tmp) / wheel_path.name
        with zipfile.ZipFile(tmp_wheel, "w") as z:
            for arc, data, mode in files:
                z.writestr(_zip_info(arc, mode), data)
        Path(wheel_directory).mkdir(parents=True, exist_ok=True)
        shutil.move(str(tmp_wheel), wheel_path)
    return wheel_path.name


def _sdist_files() -> list[str]:
    try:
        out = subprocess.run(["git", "-C", str(ROOT), "ls-files", "-z"], check=True,
                             capture_output=True).stdout
        files = [f for f in out.decode().split("\0") if f and (ROOT / f).is_file()]
        if files:
            return sorted(files)
    except (OSError, subprocess.CalledProcessError):
        pass
    files = []
    for dirpath, dirnames, filenames in os.walk(ROOT):
        dirnames[:] = sorted(d for d in dirnames if d not in SDIST_SKIP)
        for f in filenames:
            files.append(os.path.relpath(os.path.join(dirpath, f), ROOT))
    return sorted(files)


def build_sdist(sdist_directory, config_settings=None):
    project = _project()
    dist = f"{_dist_name(project)}-{project['version']}"
    path = Path(sdist_directory) / f"{dist}.tar.gz"
    Path(sdist_directory).mkdir(parents=True, exist_ok=True)
    epoch = int(os.environ.get("SOURCE_DATE_EPOCH", "315532800"))

    def add(tar: tarfile.TarFile, arcname: str, data: bytes, mode: int) -> None:
        ti = tarfile.TarInfo(f"{dist}/{arcname}")
        ti.size, ti.mode, ti.mtime = len(data), mode, epoch
        ti.uname = ti.gname = ""
        tar.addfile(ti, io.BytesIO(data))

    with tarfile.open(path, "w:gz", format=tarfile.PAX_FORMAT) as tar:
        for rel in _sdist_files():
            full = ROOT / rel
            add(tar, rel, full.read_bytes(), 0o755 if os.access(full, os.X_OK) else 0o644)
        add(tar, "PKG-INFO", _metadata(project).encode(), 0o644)
    return path.name
