"""Every default of bem_cpp in one place: the H-matrix parameters of the compressed
operators and potentials (docs/design/hmatrix.md gives the measurements behind each)."""

# Leaf size and admissibility parameter eta (docs/design/hmatrix.md, "Parameters and why").
HMATRIX_LEAF_SIZE = 48
HMATRIX_ETA = 2.0
# OpenMP threads of a product (0: all): one, for a shared machine (docs/design/hmatrix.md).
HMATRIX_PRODUCT_THREADS = 1
# V solves: relative residual solver_tol = HMATRIX_SOLVER_TOL_FACTOR * tol.
HMATRIX_SOLVER_TOL_FACTOR = 1e-3
HMATRIX_MAX_ITERATIONS = 1000
# flux "p0": accuracy of the refined-mesh V0 inside the Calderon preconditioner.
HMATRIX_PRECONDITIONER_TOL = 1e-4
# exterior_potential(compression="auto"): the H-matrix when m n >= DOFS m + POINTS n
# (the measured break-even of m points and n dofs, docs/design/hmatrix.md, "Potentials").
HMATRIX_POTENTIAL_CROSSOVER_DOFS = 1300
HMATRIX_POTENTIAL_CROSSOVER_POINTS = 1000
# Surfaces (3D): leaf size and eta of the 3D cluster trees, and the size from which
# compression="auto" takes the H-matrix S_h (docs/design/bem3d.md).
HMATRIX_SURFACE_LEAF_SIZE = 64
HMATRIX_SURFACE_ETA = 4.0
HMATRIX_SURFACE_AUTO_DOFS = 2000
# A surface's S_h holds its blocks in single precision (float: round-off 6e-8, half the
# bytes and about half the traffic of a product) when tol is at least this, so that the
# rounding stays below tol / 10 (docs/design/bem3d.md, "Single-precision storage").
HMATRIX_SINGLE_PRECISION_MIN_TOL = 1e-6
# exterior_potential of a surface: leaf size and eta of its H-matrices (points x dofs), and
# compression="auto" takes them from VERTICES vertices and POINTS points on (the measured
# break-even; docs/design/bem3d.md, "The exterior potential").
HMATRIX_SURFACE_POTENTIAL_LEAF_SIZE = 128
HMATRIX_SURFACE_POTENTIAL_ETA = 2.0
HMATRIX_SURFACE_POTENTIAL_VERTICES = 2000
HMATRIX_SURFACE_POTENTIAL_POINTS = 500
# The Lame kernel's S_h (kernel=("lame", E, nu)): compression="auto" takes the H-matrix
# operator from this many boundary nodes on (2D: at 1,000 nodes its set-up took 0.2-0.5 s
# against 1.3 s for the dense S_h; docs/design/lame_bem.md).
HMATRIX_LAME_AUTO_NODES = 1000
COMPRESSIONS = ("none", "hmatrix")
SURFACE_COMPRESSIONS = ("none", "hmatrix", "auto")
POTENTIAL_COMPRESSIONS = ("none", "hmatrix", "auto")
