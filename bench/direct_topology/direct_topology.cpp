// A probe for issue 33 (docs/design/parallel.md, "The ninth session"): a DOLFINx mesh made
// from cells that are already on their rank, by dolfinx::mesh::create_topology and
// create_geometry, without create_mesh's partitioner call, distribution, dual graph and
// cell reordering. One rank, no ghost cells: a measurement, not the project's mesh path.
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

// The mesh of the triangles ``cells`` (n x 3 global node numbers, all owned here) with the
// node coordinates ``x`` (this rank's block of the input nodes, m x gdim).
std::shared_ptr<dolfinx::mesh::Mesh> triangle_mesh(const py::object& comm_object,
                                                   const py::array_t<std::int64_t, py::array::c_style>& cells,
                                                   const py::array_t<double, py::array::c_style>& x) {
  if (cells.ndim() != 2 || cells.shape(1) != 3 || x.ndim() != 2)
    throw std::invalid_argument("cells must be n x 3 and x m x gdim");
  MPI_Comm comm = *PyMPIComm_Get(comm_object.ptr());
  const std::size_t n = cells.shape(0);
  std::vector<std::int64_t> nodes(cells.data(), cells.data() + cells.size());
  std::vector<std::int32_t> offsets(n + 1);
  for (std::size_t c = 0; c <= n; ++c) offsets[c] = static_cast<std::int32_t>(3 * c);
  const dolfinx::graph::AdjacencyList<std::int64_t> adjacency(std::move(nodes), std::move(offsets));
  std::vector<std::int64_t> original(n);
  for (std::size_t c = 0; c < n; ++c) original[c] = static_cast<std::int64_t>(c);
  const std::vector<int> no_ghosts;
  dolfinx::mesh::Topology topology = dolfinx::mesh::create_topology(
      comm, adjacency, original, no_ghosts, dolfinx::mesh::CellType::triangle, dolfinx::mesh::GhostMode::none);
  const dolfinx::fem::CoordinateElement element(dolfinx::mesh::CellType::triangle, 1);
  dolfinx::mesh::Geometry geometry = dolfinx::mesh::create_geometry(
      comm, topology, element, adjacency, std::span<const double>(x.data(), x.size()), static_cast<int>(x.shape(1)));
  return std::make_shared<dolfinx::mesh::Mesh>(comm, std::move(topology), std::move(geometry));
}

}  // namespace

PYBIND11_MODULE(direct_topology, m) {
  if (import_mpi4py() < 0) throw py::error_already_set();
  py::module::import("dolfinx.cpp");  // the Mesh type is registered there
  m.def("triangle_mesh", &triangle_mesh, py::arg("comm"), py::arg("cells"), py::arg("x"));
}
