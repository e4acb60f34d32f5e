// A probe for issue 33 (docs/design/parallel.md, "The ninth session"): a DOLFINx mesh made
// from cells that are already on their rank, by dolfinx::mesh::create_topology and
// create_geometry, without create_mesh's partitioner call, distribution, dual graph and
// cell reordering. A measurement, not the project's mesh path.
#include <mpi4py/mpi4py.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

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
#include <vector>

namespace py = pybind11;

namespace {

// The mesh of the triangles ``cells`` (n x 3 global node numbers: the cells owned here, then
// the ghost cells across their facets), numbered ``original`` in the input, with the ghost
// cells' owners ``ghost_owners`` (none: no ghost cells) and the node coordinates ``x``
// (this rank's block of the input nodes, m x gdim).
std::shared_ptr<dolfinx::mesh::Mesh> triangle_mesh(const py::object& comm_object,
                                                   const py::array_t<std::int64_t, py::array::c_style>& cells,
                                                   const py::array_t<double, py::array::c_style>& x,
                                                   const py::array_t<std::int64_t, py::array::c_style>& original,
                                                   const py::array_t<int, py::array::c_style>& ghost_owners) {
  if (cells.ndim() != 2 || cells.shape(1) != 3 || x.ndim() != 2 || original.size() != cells.shape(0) ||
      ghost_owners.size() > cells.shape(0))
    throw std::invalid_argument("cells must be n x 3, x m x gdim, original n long, ghost_owners at most n");
  MPI_Comm comm = *PyMPIComm_Get(comm_object.ptr());
  const std::size_t n = cells.shape(0);
  std::vector<std::int64_t> nodes(cells.data(), cells.data() + cells.size());
  std::vector<std::int32_t> offsets(n + 1);
  for (std::size_t c = 0; c <= n; ++c) offsets[c] = static_cast<std::int32_t>(3 * c);
  const dolfinx::graph::AdjacencyList<std::int64_t> adjacency(std::move(nodes), std::move(offsets));
  const auto mode = ghost_owners.size() ? dolfinx::mesh::GhostMode::shared_facet : dolfinx::mesh::GhostMode::none;
  dolfinx::mesh::Topology topology = dolfinx::mesh::create_topology(
      comm, adjacency, std::span<const std::int64_t>(original.data(), original.size()),
      std::span<const int>(ghost_owners.data(), ghost_owners.size()), dolfinx::mesh::CellType::triangle, mode);
  const dolfinx::fem::CoordinateElement element(dolfinx::mesh::CellType::triangle, 1);
  dolfinx::mesh::Geometry geometry = dolfinx::mesh::create_geometry(
      comm, topology, element, adjacency, std::span<const double>(x.data(), x.size()), static_cast<int>(x.shape(1)));
  return std::make_shared<dolfinx::mesh::Mesh>(comm, std::move(topology), std::move(geometry));
}

}  // namespace

PYBIND11_MODULE(direct_topology, m) {
  if (import_mpi4py() < 0) throw py::error_already_set();
  py::module::import("dolfinx.cpp");  // the Mesh type is registered there
  m.def("triangle_mesh", &triangle_mesh, py::arg("comm"), py::arg("cells"), py::arg("x"), py::arg("original"),
        py::arg("ghost_owners"));
}
