// Far-field panel pairs in batches: the tensor Gauss rule of far_blocks, evaluated for
// up to kFarBatch panels j at once with the loop over j vectorised (omp simd).
//
// The logarithm is glibc's vector log from libmvec (within 1 ulp of the scalar log on
// 4M random arguments, far below the 1e-12 target), declared here as an OpenMP simd
// function so the compiler calls _ZGV?N?v_log in the vectorised loops. The kernel is
// cloned for AVX2 and for the x86-64 baseline and picked at run time (target_clones), so
// the binary stays portable. Only this file sees the declaration: the analytic formulas in
// log_integrals.cpp keep the correctly rounded scalar log.
#include <cmath>
#include <stdexcept>
#include <type_traits>

#include "bem/far_field.hpp"

extern "C" {
#pragma omp declare simd notinbranch
double log(double x) noexcept;
}

namespace bem {

PanelArrays::PanelArrays(const Polygon& polygon) {
  std::vector<Index> all(polygon.panels().size());
  for (std::size_t j = 0; j < all.size(); ++j) all[j] = static_cast<Index>(j);
  assign(polygon, all.data(), all.size());
}

void PanelArrays::assign(const Polygon& polygon, const Index* panels, std::size_t n) {
  for (auto* v : {&ax, &ay, &tx, &ty, &nx, &ny, &h, &mx, &my}) v->resize(n);
  for (std::size_t j = 0; j < n; ++j) {
    const Panel& p = polygon.panel(panels[j]);
    ax[j] = p.a.x;
    ay[j] = p.a.y;
    tx[j] = p.t.x;
    ty[j] = p.t.y;
    nx[j] = p.n.x;
    ny[j] = p.n.y;
    h[j] = p.h;
    mx[j] = p.m.x;
    my[j] = p.m.y;
  }
}

__attribute__((target_clones("avx2", "default"))) void far_field_points(
    const Panel& pi, const PanelArrays& panels, Index j0, Index j1, int* points,
    const std::array<double, kMaxGaussPoints + 1>& y) {
  // Same test as the scalar far_field_points: the thresholds decrease with p, so the
  // number of failed ones is p - 1 (kMaxFarPoints failed: near field, 0).
  const double* mx = panels.mx.data();
  const double* my = panels.my.data();
  const double* h = panels.h.data();
#pragma omp simd
  for (Index j = j0; j < j1; ++j) {
    const double dx = pi.m.x - mx[j], dy = pi.m.y - my[j];
    const double d2 = dx * dx + dy * dy, half_sum = 0.5 * (pi.h + h[j]);
    const double half_h = 0.5 * (pi.h > h[j] ? pi.h : h[j]);
    int failed = 0;
    for (int p = 1; p <= kMaxFarPoints; ++p) {
      const double bound = half_sum + y[static_cast<std::size_t>(p)] * half_h;
      failed += d2 < bound * bound ? 1 : 0;
    }
    points[j] = failed == kMaxFarPoints ? 0 : failed + 1;
  }
}

namespace {

/// sum = term for the first term (First), sum += term for the others.
template <bool First>
inline __attribute__((always_inline)) void accumulate(double& sum, double term) {
  if constexpr (First)
    sum = term;
  else
    sum += term;
}

/// Tensor Gauss rule (p points per panel) for the pairs (i, js[k]), vectorised over k:
/// v (log kernel) if WithV, kij (double-layer kernel, normal of panel j) if WithK,
/// stored multiplied by v_scale and k_scale.
/// Accumulators start from their first term, not from zero, and the results are scaled
/// on the way out: small zero-fill and copy loops would otherwise become rep stos/movs
/// instructions, whose start-up cost exceeds the arithmetic here.
template <bool WithV, bool WithK, bool WithKji = false>
inline __attribute__((always_inline)) void far_batch(const Panel& pi, const PanelArrays& panels, const Index* js, int m,
                                                     int p, double v_scale, double k_scale,
                                                     const PairBlockColumns& out) {
  constexpr int B = kFarBatch;
  const GaussRule& g = gauss_legendre(p);
  // Panel j data, contiguous for the vector loops.
  double hj[B], dj0[B], dj1[B];
  double ox[kMaxFarPoints][B], oy[kMaxFarPoints][B], w0[kMaxFarPoints][B], w1[kMaxFarPoints][B];
  // WithKji: (y_b - x).n_i = -(a_i - y_b).n_i (t_i.n_i = 0) times the weights of point b.
  double e0[WithKji ? kMaxFarPoints : 1][B], e1[WithKji ? kMaxFarPoints : 1][B];
  for (int k = 0; k < m; ++k) {
    const std::size_t j = static_cast<std::size_t>(js[k]);
    hj[k] = panels.h[j];
    const double dx0 = pi.a.x - panels.ax[j], dy0 = pi.a.y - panels.ay[j];  // a_i - a_j
    // (x - a_j).n_j = dj0 + s dj1: affine in s, accurate even when tiny.
    dj0[k] = dx0 * panels.nx[j] + dy0 * panels.ny[j];
    dj1[k] = pi.t.x * panels.nx[j] + pi.t.y * panels.ny[j];
    for (int b = 0; b < p; ++b) {  // a_i - y_b and the shape-function weights of point b
      const double xb = g.x[static_cast<std::size_t>(b)], wb = g.w[static_cast<std::size_t>(b)];
      const double t = xb * hj[k];
      ox[b][k] = dx0 - t * panels.tx[j];
      oy[b][k] = dy0 - t * panels.ty[j];
      w0[b][k] = wb * (1.0 - xb) * hj[k];
      w1[b][k] = wb * xb * hj[k];
      if constexpr (WithKji) {
        const double di = -(ox[b][k] * pi.n.x + oy[b][k] * pi.n.y);
        e0[b][k] = w0[b][k] * di;
        e1[b][k] = w1[b][k] * di;
      }
    }
  }
  double v00[B], v01[B], v10[B], v11[B], k00[B], k01[B], k10[B], k11[B];
  for (int a = 0; a < p; ++a) {
    const double xa = g.x[static_cast<std::size_t>(a)], wa = g.w[static_cast<std::size_t>(a)];
    const double si = xa * pi.h, wi0 = wa * (1.0 - xa) * pi.h, wi1 = wa * xa * pi.h;
    const double sx = si * pi.t.x, sy = si * pi.t.y;
    // g = sum_b w_b log|x_a - y_b|, c = sum_b w_b / |x_a - y_b|^2 (shape weights of j)
    double g0[B], g1[B], c0[B], c1[B];
    // b = 0 assigns, b > 0 accumulates (two loops: a branch inside would stop the
    // vectorisation of the log calls).
    auto sweep = [&](int b, auto first) {
      const double* oxb = ox[b];
      const double* oyb = oy[b];
      const double* w0b = w0[b];
      const double* w1b = w1[b];
      const double* e0b = e0[WithKji ? b : 0];
      const double* e1b = e1[WithKji ? b : 0];
#pragma omp simd
      for (int k = 0; k < m; ++k) {
        const double rx = oxb[k] + sx, ry = oyb[k] + sy;
        const double r2 = rx * rx + ry * ry;
        constexpr bool kFirst = decltype(first)::value;
        if constexpr (WithV) {
          const double f = 0.5 * log(r2);
          accumulate<kFirst>(g0[k], w0b[k] * f);
          accumulate<kFirst>(g1[k], w1b[k] * f);
        }
        if constexpr (WithK) {
          const double inv = 1.0 / r2;
          accumulate<kFirst>(c0[k], w0b[k] * inv);
          accumulate<kFirst>(c1[k], w1b[k] * inv);
        }
        if constexpr (WithKji) {
          const double inv = 1.0 / r2;
          accumulate<kFirst>(c0[k], e0b[k] * inv);
          accumulate<kFirst>(c1[k], e1b[k] * inv);
        }
      }
    };
    sweep(0, std::true_type{});
    for (int b = 1; b < p; ++b) sweep(b, std::false_type{});
    // Outer weights: a = 0 assigns, a > 0 accumulates.
    auto add = [&](auto first) {
      auto acc = [&](double& sum, double term) { accumulate<decltype(first)::value>(sum, term); };
#pragma omp simd
      for (int k = 0; k < m; ++k) {
        if constexpr (WithV) {
          acc(v00[k], wi0 * g0[k]);
          acc(v01[k], wi0 * g1[k]);
          acc(v10[k], wi1 * g0[k]);
          acc(v11[k], wi1 * g1[k]);
        }
        if constexpr (WithK) {
          const double dj = dj0[k] + si * dj1[k];
          acc(k00[k], wi0 * dj * c0[k]);
          acc(k01[k], wi0 * dj * c1[k]);
          acc(k10[k], wi1 * dj * c0[k]);
          acc(k11[k], wi1 * dj * c1[k]);
        }
        if constexpr (WithKji) {  // k<shape on j><shape on i>
          acc(k00[k], wi0 * c0[k]);
          acc(k10[k], wi0 * c1[k]);
          acc(k01[k], wi1 * c0[k]);
          acc(k11[k], wi1 * c1[k]);
        }
      }
    };
    if (a == 0)
      add(std::true_type{});
    else
      add(std::false_type{});
  }
  // Results to the columns: contiguous runs of j (the common case on a polygon, as
  // far pairs of one panel come in order) by vector stores, otherwise scattered.
  const bool contiguous = js[m - 1] - js[0] == m - 1;
  auto put = [&](double* column, const double* values, double scale) {
    if (contiguous) {
      double* dst = column + js[0];
#pragma omp simd
      for (int k = 0; k < m; ++k) dst[k] = scale * values[k];
    } else {
      for (int k = 0; k < m; ++k) column[js[k]] = scale * values[k];
    }
  };
  if constexpr (WithV) {
    put(out.v[0][0], v00, v_scale);
    put(out.v[0][1], v01, v_scale);
    put(out.v[1][0], v10, v_scale);
    put(out.v[1][1], v11, v_scale);
  }
  if constexpr (WithK || WithKji) {
    put(out.kij[0][0], k00, k_scale);
    put(out.kij[0][1], k01, k_scale);
    put(out.kij[1][0], k10, k_scale);
    put(out.kij[1][1], k11, k_scale);
  }
}

#define BEM_FAR_BATCH_CLONE(name, with_v, with_k)                                                                  \
  __attribute__((target_clones("avx2", "default"))) void name(const Panel& pi, const PanelArrays& panels,          \
                                                              const Index* js, int m, int p, double vs, double ks, \
                                                              const PairBlockColumns& out) {                       \
    far_batch<with_v, with_k>(pi, panels, js, m, p, vs, ks, out);                                                  \
  }
BEM_FAR_BATCH_CLONE(far_batch_v, true, false)
BEM_FAR_BATCH_CLONE(far_batch_vk, true, true)
BEM_FAR_BATCH_CLONE(far_batch_k, false, true)
#undef BEM_FAR_BATCH_CLONE

__attribute__((target_clones("avx2", "default"))) void far_batch_kji(const Panel& pi, const PanelArrays& panels,
                                                                     const Index* js, int m, int p, double ks,
                                                                     const PairBlockColumns& out) {
  far_batch<false, false, true>(pi, panels, js, m, p, 1.0, ks, out);
}

}  // namespace

void far_blocks_batch(const Panel& pi, const PanelArrays& panels, const Index* js, int m, int p, bool with_v,
                      bool with_k, const PairBlockColumns& out, double v_scale, double k_scale) {
  if (m < 1 || m > kFarBatch || p < 1 || p > kMaxFarPoints || !(with_v || with_k))
    throw std::invalid_argument("far_blocks_batch: batch size, points or kernels out of range");
  if (with_v && with_k)
    far_batch_vk(pi, panels, js, m, p, v_scale, k_scale, out);
  else if (with_v)
    far_batch_v(pi, panels, js, m, p, v_scale, k_scale, out);
  else
    far_batch_k(pi, panels, js, m, p, v_scale, k_scale, out);
}

void far_kji_batch(const Panel& pi, const PanelArrays& panels, const Index* js, int m, int p,
                   const PairBlockColumns& out, double k_scale) {
  if (m < 1 || m > kFarBatch || p < 1 || p > kMaxFarPoints)
    throw std::invalid_argument("far_kji_batch: batch size or points out of range");
  far_batch_kji(pi, panels, js, m, p, k_scale, out);
}

__attribute__((target_clones("avx2", "default"))) void point_far_field_points(Vec2 z, const PanelArrays& panels,
                                                                              int* points) {
  // Same test as point_panel_moments: separation = |z - m_j| - h_j/2 >= y_p h_j/2.
  const auto& y = gauss_thresholds();
  const double* mx = panels.mx.data();
  const double* my = panels.my.data();
  const double* h = panels.h.data();
  const Index n = static_cast<Index>(panels.h.size());
#pragma omp simd
  for (Index j = 0; j < n; ++j) {
    const double dx = z.x - mx[j], dy = z.y - my[j];
    const double d2 = dx * dx + dy * dy;
    int failed = 0;
    for (int p = 1; p <= kMaxFarPoints; ++p) {
      const double bound = 0.5 * h[j] * (1.0 + y[static_cast<std::size_t>(p)]);
      failed += d2 < bound * bound ? 1 : 0;
    }
    points[j] = failed == kMaxFarPoints ? 0 : failed + 1;
  }
}

__attribute__((target_clones("avx2", "default"))) double far_point_sum(Vec2 z, const PanelArrays& panels,
                                                                       const Index* js, int m, int p, const double* l0,
                                                                       const double* l1, const double* d0,
                                                                       const double* d1) {
  constexpr int B = kFarBatch;
  const GaussRule& g = gauss_legendre(p);
  double ox[B], oy[B], tx[B], ty[B], hj[B], dn[B], cl0[B], cl1[B], cd0[B], cd1[B];
  for (int k = 0; k < m; ++k) {
    const std::size_t j = static_cast<std::size_t>(js[k]);
    ox[k] = z.x - panels.ax[j];
    oy[k] = z.y - panels.ay[j];
    tx[k] = panels.tx[j];
    ty[k] = panels.ty[j];
    hj[k] = panels.h[j];
    dn[k] = ox[k] * panels.nx[j] + oy[k] * panels.ny[j];  // (z - y).n, the same for all y
    cl0[k] = l0[j];
    cl1[k] = l1[j];
    cd0[k] = d0[j];
    cd1[k] = d1[j];
  }
  double sum = 0.0;
  for (int b = 0; b < p; ++b) {
    const double x = g.x[static_cast<std::size_t>(b)], w = g.w[static_cast<std::size_t>(b)];
#pragma omp simd reduction(+ : sum)
    for (int k = 0; k < m; ++k) {
      const double t = x * hj[k];
      const double rx = ox[k] - t * tx[k], ry = oy[k] - t * ty[k];
      const double r2 = rx * rx + ry * ry;
      const double f = 0.5 * log(r2), kd = dn[k] / r2;
      const double w0 = w * (1.0 - x) * hj[k], w1 = w * x * hj[k];
      sum += w0 * (cl0[k] * f + cd0[k] * kd) + w1 * (cl1[k] * f + cd1[k] * kd);
    }
  }
  return sum;
}

}  // namespace bem
