"""Builds the Python package with CMake: the compiled module and the project's shared libraries go
into the package folder (the module finds them beside itself), with the pure-Python files.

ORTHOFRONT_CMAKE_ARGS (space-separated) is passed to the CMake configure step, e.g.
"-DORTHOFRONT_CUDA=OFF"; ORTHOFRONT_BUILD_JOBS sets the parallel build (default: all cores).
"""
import os
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Distribution, setup
from setuptools.command.build_py import build_py

SOURCE = Path(__file__).resolve().parent


class CMakeBuild(build_py):
    def run(self):
        build = Path(self.get_finalized_command("build").build_base).resolve() / "cmake"
        stage = build.parent / "stage"
        configure = [
            "cmake", "-S", str(SOURCE), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release",
            "-DORTHOFRONT_BUILD_TESTS=OFF", "-DORTHOFRONT_PYTHON=ON",
            "-DPython3_EXECUTABLE=" + sys.executable,
            # One folder: the package, its compiled module and the libraries beside it.
            "-DORTHOFRONT_PYTHON_INSTALL_DIR=.", "-DCMAKE_INSTALL_LIBDIR=orthofront",
            "-DCMAKE_INSTALL_PREFIX=" + str(stage),
        ] + os.environ.get("ORTHOFRONT_CMAKE_ARGS", "").split()
        jobs = os.environ.get("ORTHOFRONT_BUILD_JOBS", str(os.cpu_count() or 1))
        subprocess.check_call(configure)
        subprocess.check_call(["cmake", "--build", str(build), "-j", jobs])
        shutil.rmtree(stage, ignore_errors=True)
        subprocess.check_call(["cmake", "--install", str(build)])
        package = Path(self.build_lib) / "orthofront"
        shutil.rmtree(package, ignore_errors=True)
        shutil.copytree(stage / "orthofront", package, symlinks=True,
                        ignore=shutil.ignore_patterns("cmake", "pkgconfig", "__pycache__"))


class BinaryDistribution(Distribution):
    """The package holds compiled code: its wheel is for this platform and interpreter."""

    def has_ext_modules(self):
        return True


setup(packages=["orthofront"], package_dir={"orthofront": "python/orthofront"},
      cmdclass={"build_py": CMakeBuild}, distclass=BinaryDistribution)
