"""DOLFINx side of the coupling, in layers (each imports only those before it):

- ``fem_py.parallel``, ``fem_py.polyline``, ``fem_py.tags``, ``fem_py.spec``: work done
  once on rank 0, point-set geometry, the facet tags, what Omega to build;
- ``fem_py.dofs``: the P1 space of a distributed mesh and the input numbering;
- ``fem_py.partition``: subdomains and the coarse structure;
- ``fem_py.mesh``: Omega meshed with its partition (``build_domain(comm, spec)``);
- ``fem_py.forms``: expressions, materials, the interior forms;
- ``fem_py.boundary``: the boundary map (ordered boundary nodes, T, E).
"""
