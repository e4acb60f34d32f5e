// Far-field panel pairs in batches: the tensor Gauss rule of far_blocks, evaluated for
// up to kFarBatch panels j at once with the loop over j vectorised (omp simd).
//
// The logarithm is glibc's vector log from libmvec (max error 4 ulp, i.e. 1e-15
// relative, far below the 1e-12 target), declared here as an OpenMP simd function so
// the compiler calls _ZGV?N?v_log in the vectorised loops. The kernel is cloned for
// AVX2 and for the x86-64 baseline and picked at run time (target_clones), so the
// binary stays portable. Only this file sees the declaration: the analytic formulas in
// log_integrals.cpp keep the correctly rounded scalar log.
#include <cmath>
#include <stdexcept>

#include "bem/log_integrals.hpp"

extern "C" {
#pragma omp declare simd notinbranch
double log(double x) noexcept;
}

namespace bem {

PanelArrays::PanelArrays(const Polygon& polygon) {
  const std::size_t n = polygon.panels().size();
  for (auto* v : {&ax, &ay, &tx, &ty, &nx, &ny, &h}) v->resize(n);
  for (std::size_t j = 0; j < n; ++j) {
    const Panel& p = polygon.panels()[j];
    ax[j] = p.a.x;
    ay[j] = p.a.y;
    tx[j] = p.t.x;
    ty[j] = p.t.y;
    nx[j] = p.n.x;
    ny[j] = p.n.y;
    h[j] = p.h;
  }
}

namespace {

template <bool WithK>
inline __attribute__((always_inline)) void far_batch(const Panel& pi, const PanelArrays& panels,
                                                     const Index* js, int m, int p,
                                                     const PairBlockColumns& out) {
  constexpr int B = kFarBatch;
  const GaussRule& g = gauss_legendre(p);
  // Panel j data, contiguous for the vector loops.
  double tx[B], ty[B], hj[B], dx0[B], dy0[B], dj0[B], dj1[B], di0[B], di1[B];
  for (int k = 0; k < m; ++k) {
    const std::size_t j = static_cast<std::size_t>(js[k]);
    tx[k] = panels.tx[j];
    ty[k] = panels.ty[j];
    hj[k] = panels.h[j];
    dx0[k] = pi.a.x - panels.ax[j];  // a_i - a_j
    dy0[k] = pi.a.y - panels.ay[j];
    // (x - a_j).n_j = dj0 + s dj1 and (y - a_i).n_i = di0 + t di1: affine in the local
    // coordinates, so the numerators stay accurate even when they are tiny.
    dj0[k] = dx0[k] * panels.nx[j] + dy0[k] * panels.ny[j];
    dj1[k] = pi.t.x * panels.nx[j] + pi.t.y * panels.ny[j];
    di0[k] = -(dx0[k] * pi.n.x + dy0[k] * pi.n.y);
    di1[k] = tx[k] * pi.n.x + ty[k] * pi.n.y;
  }
  // Accumulators; only the used parts are cleared (clearing whole arrays per batch
  // cost more than the arithmetic).
  double v00[B], v01[B], v10[B], v11[B], k00[B], k01[B], k10[B], k11[B];
  double q0[kMaxFarPoints][B], q1[kMaxFarPoints][B];
#pragma omp simd
  for (int k = 0; k < m; ++k) {
    v00[k] = v01[k] = v10[k] = v11[k] = 0.0;
    k00[k] = k01[k] = k10[k] = k11[k] = 0.0;
  }
  if constexpr (WithK)
    for (int b = 0; b < p; ++b)
#pragma omp simd
      for (int k = 0; k < m; ++k) q0[b][k] = q1[b][k] = 0.0;
  // Quantities of the Gauss points on panel j: y_b - a_i relative offsets and weights.
  double ox[kMaxFarPoints][B], oy[kMaxFarPoints][B], w0[kMaxFarPoints][B], w1[kMaxFarPoints][B];
  for (int b = 0; b < p; ++b) {
    const double xb = g.x[static_cast<std::size_t>(b)], wb = g.w[static_cast<std::size_t>(b)];
#pragma omp simd
    for (int k = 0; k < m; ++k) {
      const double t = xb * hj[k];
      ox[b][k] = dx0[k] - t * tx[k];  // (a_i - y_b) = ox, oy
      oy[b][k] = dy0[k] - t * ty[k];
      w0[b][k] = wb * (1.0 - xb) * hj[k];
      w1[b][k] = wb * xb * hj[k];
    }
  }
  for (int a = 0; a < p; ++a) {
    const double xa = g.x[static_cast<std::size_t>(a)], wa = g.w[static_cast<std::size_t>(a)];
    const double si = xa * pi.h, wi0 = wa * (1.0 - xa) * pi.h, wi1 = wa * xa * pi.h;
    const double sx = si * pi.t.x, sy = si * pi.t.y;
    double g0[B], g1[B], c0[B], c1[B];
#pragma omp simd
    for (int k = 0; k < m; ++k) g0[k] = g1[k] = c0[k] = c1[k] = 0.0;
    for (int b = 0; b < p; ++b) {
      const double* oxb = ox[b];
      const double* oyb = oy[b];
      const double* w0b = w0[b];
      const double* w1b = w1[b];
      double* qb0 = q0[b];
      double* qb1 = q1[b];
#pragma omp simd
      for (int k = 0; k < m; ++k) {
        const double rx = oxb[k] + sx, ry = oyb[k] + sy;
        const double r2 = rx * rx + ry * ry;
        const double f = 0.5 * log(r2);
        g0[k] += w0b[k] * f;
        g1[k] += w1b[k] * f;
        if constexpr (WithK) {
          const double inv = 1.0 / r2;
          c0[k] += w0b[k] * inv;
          c1[k] += w1b[k] * inv;
          qb0[k] += wi0 * inv;
          qb1[k] += wi1 * inv;
        }
      }
    }
#pragma omp simd
    for (int k = 0; k < m; ++k) {
      v00[k] += wi0 * g0[k];
      v01[k] += wi0 * g1[k];
      v10[k] += wi1 * g0[k];
      v11[k] += wi1 * g1[k];
      if constexpr (WithK) {
        const double dj = dj0[k] + si * dj1[k];
        k00[k] += wi0 * dj * c0[k];
        k01[k] += wi0 * dj * c1[k];
        k10[k] += wi1 * dj * c0[k];
        k11[k] += wi1 * dj * c1[k];
      }
    }
  }
  double m00[B], m01[B], m10[B], m11[B];
#pragma omp simd
  for (int k = 0; k < m; ++k) m00[k] = m01[k] = m10[k] = m11[k] = 0.0;
  if constexpr (WithK) {
    for (int b = 0; b < p; ++b) {
      const double xb = g.x[static_cast<std::size_t>(b)];
      const double* qb0 = q0[b];
      const double* qb1 = q1[b];
      const double* w0b = w0[b];
      const double* w1b = w1[b];
#pragma omp simd
      for (int k = 0; k < m; ++k) {
        const double di = di0[k] + xb * hj[k] * di1[k];
        const double wj0 = w0b[k] * di, wj1 = w1b[k] * di;
        m00[k] += wj0 * qb0[k];
        m01[k] += wj0 * qb1[k];
        m10[k] += wj1 * qb0[k];
        m11[k] += wj1 * qb1[k];
      }
    }
  }
  // Results to the columns: contiguous runs of j (the common case on a polygon, as
  // far pairs of one panel come in order) as vector copies, otherwise scattered.
  const bool contiguous = js[m - 1] - js[0] == m - 1;
  auto put = [&](double* column, const double* values) {
    if (contiguous) {
      double* dst = column + js[0];
#pragma omp simd
      for (int k = 0; k < m; ++k) dst[k] = values[k];
    } else {
      for (int k = 0; k < m; ++k) column[js[k]] = values[k];
    }
  };
  put(out.v[0][0], v00);
  put(out.v[0][1], v01);
  put(out.v[1][0], v10);
  put(out.v[1][1], v11);
  if constexpr (WithK) {
    put(out.kij[0][0], k00);
    put(out.kij[0][1], k01);
    put(out.kij[1][0], k10);
    put(out.kij[1][1], k11);
    put(out.kji[0][0], m00);
    put(out.kji[0][1], m01);
    put(out.kji[1][0], m10);
    put(out.kji[1][1], m11);
  }
}

__attribute__((target_clones("avx2", "default"))) void far_batch_v(
    const Panel& pi, const PanelArrays& panels, const Index* js, int m, int p,
    const PairBlockColumns& out) {
  far_batch<false>(pi, panels, js, m, p, out);
}

__attribute__((target_clones("avx2", "default"))) void far_batch_vk(
    const Panel& pi, const PanelArrays& panels, const Index* js, int m, int p,
    const PairBlockColumns& out) {
  far_batch<true>(pi, panels, js, m, p, out);
}

}  // namespace

void far_blocks_batch(const Panel& pi, const PanelArrays& panels, const Index* js, int m, int p,
                      bool with_k, const PairBlockColumns& out) {
  if (m < 1 || m > kFarBatch || p < 1 || p > kMaxFarPoints)
    throw std::invalid_argument("far_blocks_batch: batch size or number of points out of range");
  if (with_k)
    far_batch_vk(pi, panels, js, m, p, out);
  else
    far_batch_v(pi, panels, js, m, p, out);
}

}  // namespace bem
