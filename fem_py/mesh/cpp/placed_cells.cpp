// fem_py.mesh._placed_cells: a DOLFINx mesh made from cells that are already on the rank
// that owns them (docs/design/parallel.md, "The tenth session").
//
// The structured meshes of fem_py write each rank's own cells there, and know which of
// their neighbours' cells each rank ghosts. DOLFINx 0.5.2's create_mesh would still call a
// partitioner, send every cell to its rank (itself), build the dual graph and reorder the
// cells; its Python layer does not expose the two steps that remain,
// dolfinx::mesh::create_topology and create_geometry, which this module calls.
#include <mpi4py/mpi4py.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <dolfinx/fem/CoordinateElement.h>
#include <dolfinx/graph/AdjacencyList.h>
#include <dolfinx/mesh/Geometry.h>
#include <dolfinx/mesh/Mesh.h>
#include <dolfinx/mesh/Topology.h>
#include <dolfinx/mesh/cell_types.h>
#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace py = pybind11;

namespace {

using Int64Array = py::array_t<std::int64_t, py::array::c_style>;

// The mesh of the P1 cells ``cells`` (n x k global node numbers: this rank's own cells, then
// its ghost cells across their facets), numbered ``original`` in the input, with the ghost
// cells' owners ``ghost_owners`` and this rank's block of the input node coordinates ``x``
// (m x gdim, the blocks rank after rank). On more than one rank the cells are ghosted in
// DOLFINx's shared-facet mode, on one rank not at all.
std::shared_ptr<dolfinx::mesh::Mesh> mesh_of_placed_cells(const py::object& comm_object, const std::string& cell,
                                                          const Int64Array& cells,
                                                          const py::array_t<double, py::array::c_style>& x,
                                                          const Int64Array& original,
                                                          const py::array_t<int, py::array::c_style>& ghost_owners) {
  const dolfinx::mesh::CellType type = dolfinx::mesh::to_type(cell);
  const int k = dolfinx::mesh::num_cell_vertices(type);
  const int tdim = dolfinx::mesh::cell_dim(type);
  if (cells.ndim() != 2 || cells.shape(1) != k)
    throw std::invalid_argument("cells must be n x " + std::to_string(k) + " for a " + cell);
  if (x.ndim() != 2 || x.shape(1) < tdim)
    throw std::invalid_argument("x must be m x gdim with gdim >= " + std::to_string(tdim));
  if (original.ndim() != 1 || original.shape(0) != cells.shape(0))
    throw std::invalid_argument("original must hold one number per cell");
  if (ghost_owners.ndim() != 1 || ghost_owners.shape(0) > cells.shape(0))
    throw std::invalid_argument("ghost_owners must hold one rank per ghost cell, at most one per cell");
  MPI_Comm comm = *PyMPIComm_Get(comm_object.ptr());
  const std::size_t n = cells.shape(0);
  std::vector<std::int64_t> nodes(cells.data(), cells.data() + cells.size());
  std::vector<std::int32_t> offsets(n + 1);
  for (std::size_t c = 0; c <= n; ++c) offsets[c] = static_cast<std::int32_t>(k * c);
  const dolfinx::graph::AdjacencyList<std::int64_t> adjacency(std::move(nodes), std::move(offsets));
  int ranks = 1;
  MPI_Comm_size(comm, &ranks);
  const auto mode = ranks > 1 ? dolfinx::mesh::GhostMode::shared_facet : dolfinx::mesh::GhostMode::none;
  dolfinx::mesh::Topology topology =
      dolfinx::mesh::create_topology(comm, adjacency, std::span<const std::int64_t>(original.data(), original.size()),
                                     std::span<const int>(ghost_owners.data(), ghost_owners.size()), type, mode);
  const dolfinx::fem::CoordinateElement element(type, 1);
  dolfinx::mesh::Geometry geometry = dolfinx::mesh::create_geometry(
      comm, topology, element, adjacency, std::span<const double>(x.data(), x.size()), static_cast<int>(x.shape(1)));
  return std::make_shared<dolfinx::mesh::Mesh>(comm, std::move(topology), std::move(geometry));
}

}  // namespace

PYBIND11_MODULE(_placed_cells, m) {
  if (import_mpi4py() < 0) throw py::error_already_set();
  py::module::import("dolfinx.cpp");  // the Mesh type is registered there
  m.doc() = "A DOLFINx mesh from cells already on their ranks (create_topology + create_geometry).";
  m.def("mesh_of_placed_cells", &mesh_of_placed_cells, py::arg("comm"), py::arg("cell"), py::arg("cells"), py::arg("x"),
        py::arg("original"), py::arg("ghost_owners"));
}
