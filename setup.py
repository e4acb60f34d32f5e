"""Build of the compiled parts: ``bem_cpp._bem`` and ``fem_py.mesh._placed_cells``.

Everything else lives in pyproject.toml. The C++ sources of bem_cpp are globbed so that
the CMake build of the GoogleTest suite (bem_cpp/CMakeLists.txt) and this build always
compile the same files. ``fem_py.mesh._placed_cells`` links libdolfinx, whose compile and
link flags only DOLFINx's CMake configuration knows: it is built by CMake
(fem_py/mesh/cpp/CMakeLists.txt) into the place setuptools expects.
"""
import subprocess
import sys
from pathlib import Path

import pybind11
from pybind11.setup_helpers import ParallelCompile, Pybind11Extension, build_ext
from setuptools import Extension, setup

# the sources compile in parallel (one job per core; NPY_NUM_BUILD_JOBS overrides)
ParallelCompile("NPY_NUM_BUILD_JOBS").install()

root = Path(__file__).parent
sources = sorted(str(p.relative_to(root)) for p in (root / "bem_cpp" / "src").glob("*.cpp"))

bem = Pybind11Extension(
    "bem_cpp._bem",
    ["bem_cpp/bindings.cpp", *sources],
    include_dirs=["bem_cpp/include", "/usr/include/eigen3"],
    cxx_std=17,
    # -march=native: the module is built on the machine that runs it (make setup), and the
    # kernel loops of the 3D operators vectorise to its widest units (docs/design/bem3d.md);
    # -fno-math-errno lets sqrt vectorise.
    extra_compile_args=["-O3", "-march=native", "-fno-math-errno", "-fopenmp", "-DNDEBUG"],
    extra_link_args=["-fopenmp"],
    # Dense Cholesky, triangular solve and rank-k update of S_h (bem/linear_algebra.hpp)
    # call LAPACK/BLAS directly; on Debian these resolve to OpenBLAS (libopenblas-dev).
    # libmvec (glibc) provides the vector log of the far-field kernel (src/far_field.cpp).
    libraries=["lapack", "blas", "mvec"],
)


class CMakeExtension(Extension):
    """A module built by the CMake project in ``source_dir``, whose target is the module's
    last name."""

    def __init__(self, name: str, source_dir: str) -> None:
        super().__init__(name, sources=[])
        self.source_dir = str((root / source_dir).resolve())


class BuildExtensions(build_ext):
    """pybind11's ``build_ext``, and CMake for a :class:`CMakeExtension`."""

    def build_extension(self, ext: Extension) -> None:
        if not isinstance(ext, CMakeExtension):
            return super().build_extension(ext)
        target = Path(self.get_ext_fullpath(ext.name)).resolve()
        build = Path(self.build_temp).resolve() / ext.name
        configure = ["cmake", "-S", ext.source_dir, "-B", str(build), "-DCMAKE_BUILD_TYPE=Release"]
        configure += [f"-DPython3_EXECUTABLE={sys.executable}"]  # the one that sees mpi4py
        configure += [f"-Dpybind11_DIR={pybind11.get_cmake_dir()}"]
        configure += [f"-DCMAKE_LIBRARY_OUTPUT_DIRECTORY={target.parent}"]
        subprocess.run(configure, check=True)
        subprocess.run(["cmake", "--build", str(build), "-j", "2"], check=True)
        if not target.exists():
            raise RuntimeError(f"CMake did not write {target}")


placed_cells = CMakeExtension("fem_py.mesh._placed_cells", "fem_py/mesh/cpp")

setup(ext_modules=[bem, placed_cells], cmdclass={"build_ext": BuildExtensions})
