// pybind11 bindings of the bem_cpp core: no logic and no defaults here; those live
// in the Python wrapper bem_cpp/__init__.py. Eigen::Ref arguments map C-contiguous
// float64 numpy arrays without copies; matrices are returned by value (moved).
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>

#include "bem/boundary_operators.hpp"
#include "bem/heap.hpp"
#include "bem/kelvin.hpp"
#include "bem/lame_polygon.hpp"
#include "bem/lame_potentials.hpp"
#include "bem/lame_steklov.hpp"
#include "bem/lame_surface.hpp"
#include "bem/lame_surface_steklov.hpp"
#include "bem/linear_algebra.hpp"
#include "bem/operators.hpp"
#include "bem/potential_operator.hpp"
#include "bem/potentials.hpp"
#include "bem/sparse_cholesky.hpp"
#include "bem/steklov_operator.hpp"
#include "bem/steklov_poincare.hpp"
#include "bem/surface_operators.hpp"
#include "bem/surface_potential_operator.hpp"
#include "bem/surface_potentials.hpp"
#include "bem/surface_steklov.hpp"
#include "bem/version.hpp"

namespace py = pybind11;
using bem::Points;
using bem::Space;
using bem::Vector;
using NodesRef = const Eigen::Ref<const Points>&;
using VectorRef = const Eigen::Ref<const Vector>&;
using bem::TrianglesRef;
using bem::VerticesRef;
using Release = py::call_guard<py::gil_scoped_release>;
using Collective = std::function<Eigen::MatrixXd(const Eigen::MatrixXd&, const std::vector<bem::Index>&)>;

namespace {

/// `name`: the Lame exterior displacement or stress (`field`, bem/lame_potentials.hpp) on the
/// raw arrays of a polygon's (n, 2) nodes or of a surface's (n, 3) vertices and (m, 3)
/// triangles (validated as Polygon and Surface do).
void def_lame_exterior_field(py::module_& m, const char* name, bem::LameField field) {
  using LameRef = const bem::Lame&;
  using PointsRef3 = const Eigen::Ref<const bem::Vertices>&;
  m.def(
      name,
      [field](NodesRef nodes, LameRef lame, VectorRef dirichlet, VectorRef traction, NodesRef points, VectorRef a,
              Space space) {
        return bem::exterior_field(field, bem::Polygon(nodes), lame, dirichlet, traction, points, a, space);
      },
      py::arg("nodes"), py::arg("lame"), py::arg("dirichlet"), py::arg("traction"), py::arg("points"), py::arg("a"),
      py::arg("traction_space"), Release());
  m.def(
      name,
      [field](VerticesRef vertices, TrianglesRef triangles, LameRef lame, VectorRef dirichlet, VectorRef traction,
              PointsRef3 points, VectorRef a, Space space) {
        return bem::exterior_field(field, bem::Surface(vertices, triangles), lame, dirichlet, traction, points, a,
                                   space);
      },
      py::arg("vertices"), py::arg("triangles"), py::arg("lame"), py::arg("dirichlet"), py::arg("traction"),
      py::arg("points"), py::arg("a"), py::arg("traction_space"), Release());
}

/// The operators' communicator: none (serial) when allgather is None, otherwise the
/// collectives of the ranks (mpi4py, called back with the GIL held by pybind11's function
/// wrapper).
std::shared_ptr<const bem::Communicator> communicator(int rank, int size, Collective allgather, Collective allreduce) {
  if (!allgather) return nullptr;
  return std::make_shared<const bem::Communicator>(
      bem::Communicator{rank, size, std::move(allgather), std::move(allreduce)});
}

}  // namespace

PYBIND11_MODULE(_bem, m) {
  m.doc() = "Compiled core of bem_cpp; use the documented wrappers in bem_cpp.";
  py::enum_<Space>(m, "Space").value("P0", Space::P0).value("P1", Space::P1);
  py::class_<bem::StageTimes>(m, "StageTimes")
      .def_readonly("assembly", &bem::StageTimes::assembly)
      .def_readonly("cholesky", &bem::StageTimes::cholesky)
      .def_readonly("triangular_solve", &bem::StageTimes::triangular_solve)
      .def_readonly("rank_update", &bem::StageTimes::rank_update);

  py::class_<bem::SteklovInfo>(m, "SteklovInfo")
      .def_readonly("setup_seconds", &bem::SteklovInfo::setup_seconds)
      .def_readonly("near_field_seconds", &bem::SteklovInfo::near_field_seconds)
      .def_readonly("single_layer_seconds", &bem::SteklovInfo::single_layer_seconds)
      .def_readonly("double_layer_seconds", &bem::SteklovInfo::double_layer_seconds)
      .def_readonly("max_rank", &bem::SteklovInfo::max_rank)
      .def_readonly("nbytes_v", &bem::SteklovInfo::nbytes_v)
      .def_readonly("nbytes_v0", &bem::SteklovInfo::nbytes_v0)
      .def_readonly("nbytes_k", &bem::SteklovInfo::nbytes_k)
      .def_readonly("nbytes_w", &bem::SteklovInfo::nbytes_w)
      .def_readonly("nbytes_preconditioner", &bem::SteklovInfo::nbytes_preconditioner);
  py::class_<bem::SteklovPoincareOperator>(m, "SteklovPoincareOperator")
      .def(py::init([](NodesRef nodes, Space flux, bem::Index leaf_size, double eta, double tol,
                       double preconditioner_tol, double solver_tol, int max_iterations, int product_threads, int rank,
                       int size, Collective allgather, Collective allreduce) {
             const auto comm = communicator(rank, size, std::move(allgather), std::move(allreduce));
             return std::make_unique<bem::SteklovPoincareOperator>(
                 nodes, flux,
                 bem::SteklovOptions{{leaf_size, eta, tol, false, product_threads, comm},
                                     preconditioner_tol,
                                     solver_tol,
                                     max_iterations});
           }),
           py::arg("nodes"), py::arg("flux"), py::arg("leaf_size"), py::arg("eta"), py::arg("tol"),
           py::arg("preconditioner_tol"), py::arg("solver_tol"), py::arg("max_iterations"), py::arg("product_threads"),
           py::arg("rank"), py::arg("size"), py::arg("allgather"), py::arg("allreduce"), Release())
      .def("apply", &bem::SteklovPoincareOperator::apply, py::arg("x"), py::arg("solver_tol") = 0.0, Release())
      .def("flux", &bem::SteklovPoincareOperator::flux, py::arg("x"), py::arg("solver_tol") = 0.0, Release())
      .def_property_readonly("size", &bem::SteklovPoincareOperator::size)
      .def_property_readonly("nbytes", &bem::SteklovPoincareOperator::nbytes)
      .def_property_readonly("info", &bem::SteklovPoincareOperator::info)
      .def_property_readonly("last_iterations", &bem::SteklovPoincareOperator::last_iterations);

  py::class_<bem::LameSteklovInfo, bem::SteklovInfo>(m, "LameSteklovInfo")
      .def_readonly("hypersingular_seconds", &bem::LameSteklovInfo::hypersingular_seconds)
      .def_readonly("preconditioner_seconds", &bem::LameSteklovInfo::preconditioner_seconds)
      .def_readonly("far_field_cpu_seconds", &bem::LameSteklovInfo::far_field_cpu_seconds);
  py::class_<bem::LameSteklovOperator>(m, "LameSteklovOperator")
      .def(py::init([](NodesRef nodes, const bem::Lame& lame, Space flux, bem::Index leaf_size, double eta, double tol,
                       double preconditioner_tol, double solver_tol, int max_iterations, int product_threads, int rank,
                       int size, Collective allgather, Collective allreduce) {
             const auto comm = communicator(rank, size, std::move(allgather), std::move(allreduce));
             return std::make_unique<bem::LameSteklovOperator>(
                 nodes, lame, flux,
                 bem::SteklovOptions{{leaf_size, eta, tol, false, product_threads, comm},
                                     preconditioner_tol,
                                     solver_tol,
                                     max_iterations});
           }),
           py::arg("nodes"), py::arg("lame"), py::arg("flux"), py::arg("leaf_size"), py::arg("eta"), py::arg("tol"),
           py::arg("preconditioner_tol"), py::arg("solver_tol"), py::arg("max_iterations"), py::arg("product_threads"),
           py::arg("rank"), py::arg("size"), py::arg("allgather"), py::arg("allreduce"), Release())
      .def(py::init([](VerticesRef vertices, TrianglesRef triangles, const bem::Lame& lame, Space flux,
                       bem::Index leaf_size, double eta, double tol, double solver_tol, int max_iterations,
                       int product_threads, int rank, int size, Collective allgather, Collective allreduce,
                       bool single_precision) {
             const auto comm = communicator(rank, size, std::move(allgather), std::move(allreduce));
             bem::SteklovOptions options{
                 {leaf_size, eta, tol, false, product_threads, comm}, tol, solver_tol, max_iterations};
             options.hmatrix.single_precision = single_precision;
             return bem::lame_surface_steklov_operator(vertices, triangles, lame, flux, options);
           }),
           py::arg("vertices"), py::arg("triangles"), py::arg("lame"), py::arg("flux"), py::arg("leaf_size"),
           py::arg("eta"), py::arg("tol"), py::arg("solver_tol"), py::arg("max_iterations"), py::arg("product_threads"),
           py::arg("rank"), py::arg("size"), py::arg("allgather"), py::arg("allreduce"),
           py::arg("single_precision") = false, Release())
      .def("apply", &bem::LameSteklovOperator::apply, py::arg("x"), py::arg("solver_tol") = 0.0, Release())
      .def("flux", &bem::LameSteklovOperator::flux, py::arg("x"), py::arg("solver_tol") = 0.0, Release())
      .def("hypersingular_block", &bem::LameSteklovOperator::hypersingular_block, py::arg("nodes"), Release())
      .def_property_readonly("holds_hypersingular", &bem::LameSteklovOperator::holds_hypersingular)
      .def_property_readonly("dimension", &bem::LameSteklovOperator::dimension)
      .def_property_readonly("size", &bem::LameSteklovOperator::size)
      .def_property_readonly("nbytes", &bem::LameSteklovOperator::nbytes)
      .def_property_readonly("info", &bem::LameSteklovOperator::info)
      .def_property_readonly("last_iterations", &bem::LameSteklovOperator::last_iterations);

  py::class_<bem::BoundaryOperators>(m, "BoundaryOperators")
      .def(py::init([](NodesRef nodes, Space space, bem::Index leaf_size, double eta, double tol, int product_threads) {
             return std::make_unique<bem::BoundaryOperators>(
                 nodes, space, bem::HMatrixOptions{leaf_size, eta, tol, false, product_threads});
           }),
           py::arg("nodes"), py::arg("space"), py::arg("leaf_size"), py::arg("eta"), py::arg("tol"),
           py::arg("product_threads"), Release())
      .def("single_layer", &bem::BoundaryOperators::single_layer, py::arg("x"), Release())
      .def("double_layer", &bem::BoundaryOperators::double_layer, py::arg("x"), Release())
      .def_property_readonly("size", &bem::BoundaryOperators::size)
      .def_property_readonly("nbytes", &bem::BoundaryOperators::nbytes);

  m.def("version", &bem::version);
  m.def("single_layer", py::overload_cast<NodesRef, Space>(&bem::single_layer), py::arg("nodes"), py::arg("space"),
        Release());
  m.def("double_layer", py::overload_cast<NodesRef, Space>(&bem::double_layer), py::arg("nodes"), py::arg("space"),
        Release());
  m.def("hypersingular", py::overload_cast<NodesRef>(&bem::hypersingular), py::arg("nodes"), Release());
  m.def("single_matvec", &bem::single_matvec, py::arg("matrix"), py::arg("x"), Release());
  m.def("release_free_heap", &bem::release_free_heap, Release());
  m.def("mass", py::overload_cast<NodesRef, Space>(&bem::mass), py::arg("nodes"), py::arg("space"), Release());
  m.def("steklov_poincare", py::overload_cast<NodesRef, Space>(&bem::steklov_poincare), py::arg("nodes"),
        py::arg("flux"), Release());
  m.def("steklov_poincare_timed", &bem::steklov_poincare_timed, py::arg("nodes"), py::arg("flux"), Release());
  m.def("exterior_flux", py::overload_cast<NodesRef, VectorRef, double, Space>(&bem::exterior_flux), py::arg("nodes"),
        py::arg("dirichlet"), py::arg("a"), py::arg("flux"), Release());
  m.def("exterior_potential",
        py::overload_cast<NodesRef, VectorRef, VectorRef, NodesRef, double, Space>(&bem::exterior_potential),
        py::arg("nodes"), py::arg("dirichlet"), py::arg("flux_coefficients"), py::arg("points"), py::arg("a"),
        py::arg("flux"), Release());
  m.def(
      "exterior_potential_hmatrix",
      [](NodesRef nodes, VectorRef dirichlet, VectorRef flux_coefficients, NodesRef points, double a, Space flux,
         bem::Index leaf_size, double eta, double tol, int product_threads) {
        return bem::exterior_potential_hmatrix(nodes, dirichlet, flux_coefficients, points, a, flux,
                                               bem::HMatrixOptions{leaf_size, eta, tol, false, product_threads});
      },
      py::arg("nodes"), py::arg("dirichlet"), py::arg("flux_coefficients"), py::arg("points"), py::arg("a"),
      py::arg("flux"), py::arg("leaf_size"), py::arg("eta"), py::arg("tol"), py::arg("product_threads"), Release());

  // Surfaces in 3D: the same names, told apart by their arguments (vertices, triangles, ...).
  m.def("single_layer", py::overload_cast<VerticesRef, TrianglesRef, Space>(&bem::single_layer), py::arg("vertices"),
        py::arg("triangles"), py::arg("space"), Release());
  m.def("double_layer", py::overload_cast<VerticesRef, TrianglesRef, Space>(&bem::double_layer), py::arg("vertices"),
        py::arg("triangles"), py::arg("space"), Release());
  m.def("hypersingular", py::overload_cast<VerticesRef, TrianglesRef>(&bem::hypersingular), py::arg("vertices"),
        py::arg("triangles"), Release());
  m.def("hypersingular_block",
        py::overload_cast<VerticesRef, TrianglesRef, const std::vector<bem::Index>&>(&bem::hypersingular_block),
        py::arg("vertices"), py::arg("triangles"), py::arg("block"), Release());
  m.def(
      "surface_operators",
      [](VerticesRef vertices, TrianglesRef triangles, Space space) {
        // V_h and K_h (rows in `space`) and W_h in one pass over the triangle pairs
        bem::SurfaceMatrices A = bem::assemble(bem::Surface(vertices, triangles), {space, space, true});
        return py::make_tuple(std::move(A.single_layer), std::move(A.double_layer), std::move(A.hypersingular));
      },
      py::arg("vertices"), py::arg("triangles"), py::arg("space"));
  m.def("mass", py::overload_cast<VerticesRef, TrianglesRef, Space>(&bem::mass), py::arg("vertices"),
        py::arg("triangles"), py::arg("space"), Release());
  m.def("exterior_potential",
        py::overload_cast<VerticesRef, TrianglesRef, VectorRef, VectorRef, const Eigen::Ref<const bem::Vertices>&,
                          double, Space>(&bem::exterior_potential),
        py::arg("vertices"), py::arg("triangles"), py::arg("dirichlet"), py::arg("flux_coefficients"),
        py::arg("points"), py::arg("a"), py::arg("flux"), Release());
  m.def(
      "exterior_potential_hmatrix",
      [](VerticesRef vertices, TrianglesRef triangles, VectorRef dirichlet, VectorRef flux_coefficients,
         const Eigen::Ref<const bem::Vertices>& points, double a, Space flux, bem::Index leaf_size, double eta,
         double tol, int product_threads) {
        return bem::exterior_potential_hmatrix(vertices, triangles, dirichlet, flux_coefficients, points, a, flux,
                                               bem::HMatrixOptions{leaf_size, eta, tol, false, product_threads});
      },
      py::arg("vertices"), py::arg("triangles"), py::arg("dirichlet"), py::arg("flux_coefficients"), py::arg("points"),
      py::arg("a"), py::arg("flux"), py::arg("leaf_size"), py::arg("eta"), py::arg("tol"), py::arg("product_threads"),
      Release());
  // Linear elasticity (Kelvin's kernel): the Lame twins of the Laplace functions, the medium after the geometry.
  py::class_<bem::Lame>(m, "Lame")
      .def_readonly("mu", &bem::Lame::mu)
      .def_readonly("nu", &bem::Lame::nu)
      .def_property_readonly("lame_lambda", &bem::Lame::lambda)
      .def("__repr__",
           [](const bem::Lame& l) { return "Lame(mu=" + std::to_string(l.mu) + ", nu=" + std::to_string(l.nu) + ")"; });
  m.def("lame_from_young", &bem::lame_from_young, py::arg("E"), py::arg("nu"));
  m.def(
      "kelvin_field",
      [](const bem::Lame& lame, const Eigen::Ref<const bem::Matrix>& points, VectorRef source, VectorRef force) {
        bem::PointForceField f = bem::kelvin_field(lame, points, source, force);
        return py::make_tuple(std::move(f.displacement), std::move(f.stress));
      },
      py::arg("lame"), py::arg("points"), py::arg("source"), py::arg("force"));
  using LameRef = const bem::Lame&;
  m.def(
      "lame_critical_scale",
      [](NodesRef nodes, LameRef lame, Space space) {
        return bem::single_layer_critical_scale(bem::Polygon(nodes), lame, space);
      },
      py::arg("nodes"), py::arg("lame"), py::arg("space"), Release());
  m.def("lame_single_layer", py::overload_cast<NodesRef, LameRef, Space>(&bem::single_layer), py::arg("nodes"),
        py::arg("lame"), py::arg("space"), Release());
  m.def("lame_double_layer", py::overload_cast<NodesRef, LameRef, Space>(&bem::double_layer), py::arg("nodes"),
        py::arg("lame"), py::arg("space"), Release());
  m.def("lame_hypersingular", py::overload_cast<NodesRef, LameRef>(&bem::hypersingular), py::arg("nodes"),
        py::arg("lame"), Release());
  m.def("lame_single_layer", py::overload_cast<VerticesRef, TrianglesRef, LameRef, Space>(&bem::single_layer),
        py::arg("vertices"), py::arg("triangles"), py::arg("lame"), py::arg("space"), Release());
  m.def("lame_double_layer", py::overload_cast<VerticesRef, TrianglesRef, LameRef, Space>(&bem::double_layer),
        py::arg("vertices"), py::arg("triangles"), py::arg("lame"), py::arg("space"), Release());
  m.def("lame_hypersingular", py::overload_cast<VerticesRef, TrianglesRef, LameRef>(&bem::hypersingular),
        py::arg("vertices"), py::arg("triangles"), py::arg("lame"), Release());
  def_lame_exterior_field(m, "lame_exterior_displacement", bem::LameField::Displacement);
  def_lame_exterior_field(m, "lame_exterior_stress", bem::LameField::Stress);
  m.def(
      "lame_operators",
      [](NodesRef nodes, LameRef lame, Space space) {
        // V_h and K_h (rows in `space`) and W_h in one pass over the panel pairs
        bem::Operators A;
        {
          py::gil_scoped_release release;
          A = bem::assemble(bem::Polygon(nodes), lame, {space, space, true});
        }
        return py::make_tuple(std::move(A.single_layer), std::move(A.double_layer), std::move(A.hypersingular));
      },
      py::arg("nodes"), py::arg("lame"), py::arg("space"));
  m.def(
      "lame_operators",
      [](VerticesRef vertices, TrianglesRef triangles, LameRef lame, Space space) {
        bem::SurfaceMatrices A;
        {
          py::gil_scoped_release release;
          A = bem::assemble(bem::Surface(vertices, triangles), lame, {space, space, true});
        }
        return py::make_tuple(std::move(A.single_layer), std::move(A.double_layer), std::move(A.hypersingular));
      },
      py::arg("vertices"), py::arg("triangles"), py::arg("lame"), py::arg("space"));
  py::class_<bem::SurfaceSteklovOperator>(m, "SurfaceSteklovOperator")
      .def(py::init([](VerticesRef vertices, TrianglesRef triangles, bem::Index leaf_size, double eta, double tol,
                       double solver_tol, int max_iterations, int product_threads, int rank, int size,
                       Collective allgather, Collective allreduce, bool single_precision) {
             const auto comm = communicator(rank, size, std::move(allgather), std::move(allreduce));
             bem::SteklovOptions options{
                 {leaf_size, eta, tol, false, product_threads, comm}, tol, solver_tol, max_iterations};
             options.hmatrix.single_precision = single_precision;
             return std::make_unique<bem::SurfaceSteklovOperator>(vertices, triangles, options);
           }),
           py::arg("vertices"), py::arg("triangles"), py::arg("leaf_size"), py::arg("eta"), py::arg("tol"),
           py::arg("solver_tol"), py::arg("max_iterations"), py::arg("product_threads"), py::arg("rank"),
           py::arg("size"), py::arg("allgather"), py::arg("allreduce"), py::arg("single_precision") = false, Release())
      .def("apply", &bem::SurfaceSteklovOperator::apply, py::arg("x"), py::arg("solver_tol") = 0.0, Release())
      .def("flux", &bem::SurfaceSteklovOperator::flux, py::arg("x"), py::arg("solver_tol") = 0.0, Release())
      .def("single_layer", &bem::SurfaceSteklovOperator::single_layer, py::arg("x"), Release())
      .def("double_layer", &bem::SurfaceSteklovOperator::double_layer, py::arg("x"), Release())
      .def("hypersingular", &bem::SurfaceSteklovOperator::hypersingular, py::arg("x"), Release())
      .def("hypersingular_block", &bem::SurfaceSteklovOperator::hypersingular_block, py::arg("indices"), Release())
      .def("hypersingular_block_single", &bem::SurfaceSteklovOperator::hypersingular_block_single, py::arg("indices"),
           Release())
      .def_property_readonly("size", &bem::SurfaceSteklovOperator::size)
      .def_property_readonly("nbytes", &bem::SurfaceSteklovOperator::nbytes)
      .def_property_readonly("info", &bem::SurfaceSteklovOperator::info)
      .def_property_readonly("last_iterations", &bem::SurfaceSteklovOperator::last_iterations);
  using bem::SparseCholesky;
  py::register_exception<bem::NotPositiveDefinite>(m, "NotPositiveDefinite", PyExc_ArithmeticError);
  using IndicesRef = const Eigen::Ref<const SparseCholesky::Indices>&;
  py::class_<SparseCholesky>(m, "SparseCholesky")
      .def(py::init<bem::Index, IndicesRef, IndicesRef, VectorRef, IndicesRef, bem::Index>(), py::arg("n"),
           py::arg("indptr"), py::arg("indices"), py::arg("data"), py::arg("ordering"), py::arg("n_schur") = 0,
           Release())
      .def("solve", &SparseCholesky::solve, py::arg("B"), Release())
      .def("eliminate", &SparseCholesky::eliminate, py::arg("B"), Release())
      .def("back_substitute", &SparseCholesky::back_substitute, py::arg("W"), Release())
      .def_property_readonly("schur", &SparseCholesky::schur)
      .def_property_readonly("factor_nonzeros", &SparseCholesky::factor_nonzeros);
}
