"""Builds the zeroset Python module with the project's CMake (python/CMakeLists.txt).

`python3 -m pip install --no-build-isolation .` (docs/python.md) runs this: CMake configures the
repository with only what the module needs, builds the `_zeroset` extension and puts it into
the package setuptools installs. Extra CMake arguments: the ZEROSET_CMAKE_ARGS environment
variable (e.g. "-DZEROSET_NATIVE=OFF" for a build that runs on other processors).
"""
import os
import pathlib
import shlex
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        target = pathlib.Path(self.get_ext_fullpath(ext.name)).resolve()
        build = pathlib.Path(self.build_temp).resolve() / "cmake"
        build.mkdir(parents=True, exist_ok=True)
        configure = [
            "cmake", "-S", str(ROOT), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release",
            f"-DPython_EXECUTABLE={sys.executable}", "-DZEROSET_BUILD_PYTHON=ON",
            "-DZEROSET_BUILD_TESTS=OFF", "-DZEROSET_BUILD_BENCH=OFF",
            "-DZEROSET_BUILD_VIEWER=OFF", "-DZEROSET_BUILD_EXAMPLES=OFF",
        ] + shlex.split(os.environ.get("ZEROSET_CMAKE_ARGS", ""))
        subprocess.run(configure, check=True)
        jobs = str(os.cpu_count() or 1)
        subprocess.run(["cmake", "--build", str(build), "--target", "_zeroset", "-j", jobs],
                       check=True)
        built = sorted((build / "python" / "zeroset").glob("_zeroset*.so"))
        if not built:
            raise RuntimeError(f"the CMake build made no _zeroset extension in {build}")
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[0], target)


setup(
    packages=["zeroset"],
    package_dir={"": "python"},
    ext_modules=[Extension("zeroset._zeroset", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    # Beside the CMake build directory's own files, not among them.
    options={"build": {"build_base": "build/pip"}},
    zip_safe=False,
)
