"""The P1 dofs of a distributed mesh: the P1 space (created in one place), its dof
topology and exterior facet data (``p1``), and the input numbering of its nodes with the
gathers to rank 0 that do not depend on the number of ranks (``numbering``)."""
from fem_py.dofs.numbering import (
    gather_by_input,
    gather_cells,
    gather_p1,
    gather_p1_and_cells,
    input_indices,
    input_node_numbers,
)
from fem_py.dofs.p1 import (
    FacetData,
    P1Topology,
    exterior_facets,
    facet_data,
    gather_facet_data,
    p1_space,
    p1_topology,
    quiet_jit,
    tag_array,
)

__all__ = [
    "FacetData",
    "P1Topology",
    "exterior_facets",
    "facet_data",
    "gather_by_input",
    "gather_cells",
    "gather_facet_data",
    "gather_p1",
    "gather_p1_and_cells",
    "input_indices",
    "input_node_numbers",
    "p1_space",
    "p1_topology",
    "quiet_jit",
    "tag_array",
]
