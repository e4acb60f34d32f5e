#include "bem/lame_surface.hpp"

#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "bem/block3.hpp"

namespace bem {

namespace {

/// The 3 x 3 block of node pair (p, q) of a matrix with node-major dofs: A(3 p + k, 3 q + l) += s B[k][l].
void add(Matrix& A, Index p, Index q, double s, const Block& B) {
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l) A(3 * p + k, 3 * q + l) += s * B[k][l];
}

/// The surface curls of a triangle's hats and their cross matrices.
struct Curls {
  double c[3][3];  ///< c[j][k]: component k of curl lambda_j
  Block A[3];      ///< [curl lambda_j]_x
  explicit Curls(const Triangle& t) {
    for (int j = 0; j < 3; ++j) {
      const Vec3 v = surface_curl(t, j);
      c[j][0] = v.x;
      c[j][1] = v.y;
      c[j][2] = v.z;
      cross_matrix(v, A[j]);
    }
  }
};

}  // namespace

SurfaceMatrices assemble(const Surface& surface, const Lame& m, const SurfaceRequest& request) {
  check_medium(m);
  // As the Laplace assembly (surface_operators.cpp): each unordered pair {tau, sigma} once
  // (tau <= sigma); V and W accumulated as their upper parts H (tau = sigma halved) and
  // completed as H + H^T; K as the rows of tau plus, transposed, the rows of sigma (Kt by the
  // rows of tau's vertices). Threads own the rows of tau's vertices (colouring).
  const Index nt = surface.size(), n = surface.vertices();
  const std::optional<Space> vs = request.single_layer, ks = request.double_layer;
  const bool k = ks.has_value(), w = request.hypersingular;
  Matrix V, K, Kt, W;
  if (vs) V = Matrix::Zero(3 * dofs(surface, *vs), 3 * dofs(surface, *vs));
  if (k) {
    K = Matrix::Zero(3 * dofs(surface, *ks), 3 * n);
    Kt = Matrix::Zero(3 * n, 3 * dofs(surface, *ks));
  }
  if (w) W = Matrix::Zero(3 * n, 3 * n);
  // the coefficients of the header's formulas
  const double mu = m.mu, nu = m.nu, a = 3.0 - 4.0 * nu, cu = 1.0 / (4.0 * mu * (1.0 - nu));
  const double kg = (1.0 - 2.0 * nu) / (2.0 * (1.0 - nu)), kr = 1.0 / (2.0 * (1.0 - nu)), wr = mu / (1.0 - nu);
  const bool p0v = vs && *vs == Space::P0, p0k = k && *ks == Space::P0;
  const PairIntegrator integrator(surface);
  for_each_triangle_by_colour(surface, [&](Index tau) {
    const Triangle& ta = surface.triangle(tau);
    const Curls ca(ta);
    PairMoments L;
    Block B, RA;
    // the block [2 int int U_kl phi_i(x) phi_j(y)]_kl (x in tau, y in sigma)
    auto single_layer_block = [&](int i, int j, Block& U) {
      for (int kk = 0; kk < 3; ++kk)
        for (int l = 0; l < 3; ++l) U[kk][l] = cu * ((kk == l ? a * L.G[i][j] : 0.0) + L.R[kk][l][i][j]);
    };
    // the block of K: test basis i, trial hat with cross matrix A (D: the Laplace double layer,
    // g: the moment of G, R: of r r^T / |r|^3, test basis against the constant)
    auto double_layer_block = [&](double D, double g, const Block& R, const Block& A) {
      product(R, A, RA);
      for (int kk = 0; kk < 3; ++kk)
        for (int l = 0; l < 3; ++l) B[kk][l] = (kk == l ? D : 0.0) + kg * g * A[kk][l] + kr * RA[kk][l];
    };
    for (Index sigma = tau; sigma < nt; ++sigma) {
      integrator.moments(tau, sigma, k, L);
      const Triangle& tb = surface.triangle(sigma);
      const Curls cb(tb);
      const double half = sigma == tau ? 0.5 : 1.0;
      if (vs) {
        if (p0v) {
          single_layer_block(3, 3, B);
          add(V, tau, sigma, half, B);
        } else {
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
              single_layer_block(i, j, B);
              add(V, ta.v[i], tb.v[j], half, B);
            }
        }
      }
      if (k) {
        const int first = p0k ? 3 : 0, last = p0k ? 4 : 3;
        Block R;
        for (int i = first; i < last; ++i) {
          for (int kk = 0; kk < 3; ++kk)
            for (int l = 0; l < 3; ++l) R[kk][l] = L.R[kk][l][i][3];
          for (int j = 0; j < 3; ++j) {
            double_layer_block(L.K[i][j], L.G[i][3], R, cb.A[j]);
            add(K, p0k ? tau : ta.v[i], tb.v[j], 1.0, B);
          }
        }
        if (sigma != tau)  // the pair (sigma, tau): test basis i of sigma, trial hat j of tau
          for (int i = first; i < last; ++i) {
            for (int kk = 0; kk < 3; ++kk)
              for (int l = 0; l < 3; ++l) R[kk][l] = L.R[kk][l][3][i];
            for (int j = 0; j < 3; ++j) {
              double_layer_block(L.Kt[i][j], L.G[3][i], R, ca.A[j]);
              // transposed: Kt(3 tau_j + l, 3 sigma_i + k) += B[k][l]
              const Index row = ta.v[j], col = p0k ? sigma : tb.v[i];
              for (int l = 0; l < 3; ++l)
                for (int kk = 0; kk < 3; ++kk) Kt(3 * row + l, 3 * col + kk) += B[kk][l];
            }
          }
      }
      if (w) {
        const double g = wr * L.G[3][3];
        Block R, RA3[3];
        for (int kk = 0; kk < 3; ++kk)
          for (int l = 0; l < 3; ++l) R[kk][l] = L.R[kk][l][3][3];
        for (int j = 0; j < 3; ++j) product(R, cb.A[j], RA3[j]);
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) {
            const double* ci = ca.c[i];
            const double* cj = cb.c[j];
            const double cc = ci[0] * cj[0] + ci[1] * cj[1] + ci[2] * cj[2];
            product(ca.A[i], RA3[j], B);
            for (int kk = 0; kk < 3; ++kk)
              for (int l = 0; l < 3; ++l)
                B[kk][l] = wr * B[kk][l] +
                           g * ((kk == l ? cc : 0.0) + (1.0 - 2.0 * nu) * cj[kk] * ci[l] - (1.0 - nu) * ci[kk] * cj[l]);
            add(W, ta.v[i], tb.v[j], half, B);
          }
      }
    }
  });
  SurfaceMatrices out;
  if (vs) out.single_layer = V + V.transpose();
  if (k) out.double_layer = K + Kt.transpose();
  if (w) out.hypersingular = W + W.transpose();
  return out;
}

Matrix single_layer(VerticesRef vertices, TrianglesRef triangles, const Lame& m, Space space) {
  SurfaceRequest r;
  r.single_layer = space;
  return assemble(Surface(vertices, triangles), m, r).single_layer;
}

Matrix double_layer(VerticesRef vertices, TrianglesRef triangles, const Lame& m, Space space) {
  SurfaceRequest r;
  r.double_layer = space;
  return assemble(Surface(vertices, triangles), m, r).double_layer;
}

Matrix hypersingular(VerticesRef vertices, TrianglesRef triangles, const Lame& m) {
  SurfaceRequest r;
  r.hypersingular = true;
  return assemble(Surface(vertices, triangles), m, r).hypersingular;
}

}  // namespace bem
