"""Builds adamesh._adamesh with CMake (see pyproject.toml and docs/PYTHON.md)."""
import os
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent


class CMakeExtension(Extension):
    def __init__(self, name: str) -> None:
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    """Configures the repository with ADAMESH_BUILD_PYTHON=ON and builds the _adamesh target
    straight into the wheel's adamesh/ directory."""

    def build_extension(self, ext: Extension) -> None:
        package_parent = Path(self.get_ext_fullpath(ext.name)).resolve().parent.parent
        build = Path(self.build_temp).resolve() / "cmake"
        generator = ["-G", "Ninja"] if shutil.which("ninja") else []
        subprocess.check_call([
            "cmake", "-S", str(ROOT), "-B", str(build), *generator,
            "-DCMAKE_BUILD_TYPE=Release", "-DADAMESH_BUILD_TESTS=OFF", "-DADAMESH_INSTALL=OFF",
            "-DADAMESH_BUILD_PYTHON=ON", f"-DPython3_EXECUTABLE={sys.executable}",
            f"-DADAMESH_PYTHON_OUTPUT_DIR={package_parent}"])
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 2))
        subprocess.check_call(["cmake", "--build", str(build), "--target", "_adamesh", "-j", jobs])


setup(ext_modules=[CMakeExtension("adamesh._adamesh")], cmdclass={"build_ext": CMakeBuild})
