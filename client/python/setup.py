"""Builds the compiled parts of the package geodex with CMake, for pip.

pyproject.toml holds the package's metadata; this file adds what
setuptools cannot do alone: configure the repository root with CMake,
build the two targets the package needs (geodex_python_core: the module
geodex._core; geodex_python: the gRPC stubs geodex.v1, generated from the
proto) and put them into the wheel beside the pure-Python modules.

Environment:
  GEODEX_CMAKE_BUILD_DIR  an existing, configured build tree of this
                          repository (e.g. build/): its two targets are
                          brought up to date and taken from it, instead of
                          configuring a tree of the package's own.
  CMAKE_ARGS              more arguments for the configure step (e.g.
                          "-DCMAKE_CXX_COMPILER_LAUNCHER=ccache").
  CMAKE_BUILD_PARALLEL_LEVEL  compile jobs (CMake's own variable).
  GEODEX_SETUP_BUILD_BASE     where setuptools stages the package (default
                          build/ here): a fresh folder makes sure nothing
                          stale from an earlier build gets into the wheel.
"""

from __future__ import annotations

import glob
import os
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]  # client/python -> the repository
TARGETS = ["geodex_python_core", "geodex_python"]


class CMakeExtension(Extension):
    """An extension CMake builds: no sources for setuptools to compile."""

    def __init__(self, name: str) -> None:
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def run(self) -> None:
        if self.inplace:
            sys.exit("geodex: in-place (editable) builds are not supported; pip install ./client/python")
        if not (ROOT / "CMakeLists.txt").is_file() or not (ROOT / "core").is_dir():
            sys.exit(
                f"geodex: {ROOT} is not the geodex repository; the package builds from "
                "client/python inside a checkout (pip install ./client/python)"
            )
        tree = self._cmake_tree()
        command = ["cmake", "--build", str(tree), "--target", *TARGETS]
        if self.parallel:
            command += ["--parallel", str(self.parallel)]
        subprocess.run(command, check=True)
        self._collect(tree / "python" / "geodex")

    def _cmake_tree(self) -> Path:
        existing = os.environ.get("GEODEX_CMAKE_BUILD_DIR")
        if existing:
            tree = Path(existing).resolve()
            if not (tree / "CMakeCache.txt").is_file():
                sys.exit(f"geodex: GEODEX_CMAKE_BUILD_DIR={existing} is not a configured build tree")
            return tree
        tree = Path(self.build_temp).resolve() / "cmake"
        configure = [
            "cmake", "-S", str(ROOT), "-B", str(tree),
            "-DCMAKE_BUILD_TYPE=Release",
            # Only the package's two targets are built; tests, benchmarks and
            # the CGAL cross-checks need not even be configured.
            "-DGEODEX_BUILD_TESTS=OFF", "-DGEODEX_BUILD_BENCHMARKS=OFF", "-DGEODEX_WITH_CGAL=OFF",
            f"-DPython3_EXECUTABLE={sys.executable}",
        ]
        if shutil.which("ninja") and not (tree / "CMakeCache.txt").exists():
            configure += ["-G", "Ninja"]  # a tree keeps the generator it was made with
        configure += shlex.split(os.environ.get("CMAKE_ARGS", ""))
        subprocess.run(configure, check=True)
        return tree

    def _collect(self, assembled: Path) -> None:
        """The module and the stubs, from the tree's assembled package into
        the wheel's."""
        suffix = sysconfig.get_config_var("EXT_SUFFIX")
        module = assembled / f"_core{suffix}"
        if not module.is_file():
            found = sorted(os.path.basename(p) for p in glob.glob(str(assembled / "_core*")))
            sys.exit(
                f"geodex: {module} was not built (found: {found or 'nothing'}); the CMake "
                f"tree's Python must be this one ({sys.executable})"
            )
        destination = Path(self.get_ext_fullpath("geodex._core"))
        destination.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(module, destination)
        stubs = Path(self.build_lib) / "geodex" / "v1"
        stubs.mkdir(parents=True, exist_ok=True)
        for name in ("__init__.py", "geodex_pb2.py", "geodex_pb2_grpc.py"):
            shutil.copyfile(assembled / "v1" / name, stubs / name)


def version() -> str:
    match = re.search(r'^__version__ = "([^"]+)"', (HERE / "geodex" / "__init__.py").read_text(), re.M)
    assert match, "geodex/__init__.py sets no __version__"
    return match.group(1)


_base = os.environ.get("GEODEX_SETUP_BUILD_BASE")
if _base:
    os.makedirs(_base, exist_ok=True)
setup(
    version=version(),
    packages=["geodex"],
    package_data={"geodex": ["py.typed", "*.pyi"]},
    ext_modules=[CMakeExtension("geodex._core")],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": _base}, "egg_info": {"egg_base": _base}} if _base else {},
)
