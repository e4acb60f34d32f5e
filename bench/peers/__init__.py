"""Peer benchmark: the project's solvers against PETSc's VI and bound-constrained solvers.

Is PGPM faster than PETSc's own solvers on the same discrete problem (2.3), and how far
is it from the cost of one linear solve? Every solver solves the same problem on the
same mesh (the square [-1/4, 1/4]^2, structured, d/h = 4, Signorini arc = bottom side,
carstensen material), for two data sets:

* ``manufactured``: ``coupling.manufactured.square_contact`` (exact solution known);
* ``load``: f = 2, t0 = -1, u0 = 0.1 x, a = 0 (no exact solution).

Solvers (``bench.peers.baselines`` sets them all up):

    (a) PGPM + substructuring preconditioner (the paper's method)
    (b) PGPM + identity (small sizes only), APGPM and SSN (the default method) + substructuring
    (c) PETSc SNES vinewtonrsls on the optimality system, with several linear solvers,
        from x = 0 and grid-sequenced (coarser levels first, each solution prolonged)
    (d) PETSc TAO BLMVM, BQNLS (J_h and gradient), BNLS and BNTR (with the Hessian)
    (e) yardstick: one P1 Poisson solve, CG + GAMG to rtol 1e-8

Each size runs in its own worker process (``--worker``); inside it every solver gets
its own window for wall time and peak memory (the Linux high-water mark VmHWM is reset
through /proc/self/clear_refs before each solver). Solutions are compared with PGPM's.

    .venv/bin/python -m bench.peers [--quick] [--json] [--sizes 100,250,500,1000]
                                    [--solvers pgpm,ssn,...] [--out DIR]
                                    [--budget SECONDS] [--report-from FILE]

from the root of the source tree (``make bench`` runs it with the other benchmarks).

``--quick`` (sizes 100 and 200, a handful of solvers) prints the table and writes
results only when ``--out`` is given; the full run writes ``bench/results.md``,
``bench/peers.png`` and the raw records ``bench/results.json``, from which
``--report-from`` rewrites the first two without rerunning. Exit code 0, or 1 when a
worker process crashed. Serial: under mpirun it exits with code 2 and a message.
Run times and the measurements behind the tolerances: docs/design/baselines.md.

The modules: :mod:`~bench.peers.cli` (the command line), :mod:`~bench.peers.runner`
(one worker process per size), :mod:`~bench.peers.worker` (the solves of one size),
:mod:`~bench.peers.solvers` (the solver table, sizes and tolerances),
:mod:`~bench.peers.targets` (the verdicts), :mod:`~bench.peers.tables` (the table of
runs and the figure), :mod:`~bench.peers.report` (``results.md``),
:mod:`~bench.peers.baselines` (the PETSc peers themselves).
"""
