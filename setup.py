"""Build of the compiled part of bem_cpp (``bem_cpp._bem``).

Everything else lives in pyproject.toml. The C++ sources are globbed so that the
CMake build of the GoogleTest suite (bem_cpp/CMakeLists.txt) and this build always
compile the same files.
"""
from pathlib import Path

from pybind11.setup_helpers import ParallelCompile, Pybind11Extension, build_ext
from setuptools import setup

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

setup(ext_modules=[bem], cmdclass={"build_ext": build_ext})
