#include "bem/far_points.hpp"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <utility>

namespace bem {

std::vector<Part> parts(const Surface& s, Space space, const Index* dofs, Index k) {
  // (triangle, basis, position) as one key, sorted: triangle << 34 | basis << 32 | position
  // (the order of the triples; a sort of integers, several times faster than of tuples)
  if (s.size() >= (Index{1} << 30) || k >= (Index{1} << 32))
    throw std::invalid_argument("parts: more than 2^30 triangles or 2^32 dofs");
  std::vector<std::uint64_t> keys;
  keys.reserve(static_cast<std::size_t>(space == Space::P0 ? k : 7 * k));
  auto key = [](Index t, int basis, Index p) {
    return static_cast<std::uint64_t>(t) << 34 | static_cast<std::uint64_t>(basis) << 32 |
           static_cast<std::uint64_t>(p);
  };
  for (Index p = 0; p < k; ++p) {
    const Index d = dofs[p];
    if (space == Space::P0) {
      keys.push_back(key(d, 3, p));
    } else {
      for (Index t : s.star(d)) {
        const Triangle& T = s.triangle(t);
        const int a = static_cast<int>(std::find(T.v.begin(), T.v.end(), d) - T.v.begin());
        keys.push_back(key(t, a, p));
      }
    }
  }
  std::sort(keys.begin(), keys.end());
  std::vector<Part> out;
  for (const std::uint64_t item : keys) {
    const Index t = static_cast<Index>(item >> 34);
    if (out.empty() || out.back().triangle != t) out.push_back(Part{t, 0, {0, 0, 0}, {0, 0, 0}});
    Part& q = out.back();
    q.basis[q.count] = static_cast<int>(item >> 32 & 3);
    q.position[q.count] = static_cast<Index>(item & 0xFFFFFFFF);
    ++q.count;
  }
  return out;
}

FarPoints::FarPoints(const Surface& s, const std::vector<Part>& parts, Index dofs, bool with_curls,
                     const TriangleRule& r) {
  std::vector<Eigen::Triplet<double>> entries[3];
  per_part = r.size();
  for (auto* v : {&x, &y, &z, &nx, &ny, &nz, &w}) v->reserve(parts.size() * static_cast<std::size_t>(r.size()));
  Index part_index = 0;
  for (const Part& part : parts) {
    const Triangle& T = s.triangle(part.triangle);
    for (int q = 0; q < r.size(); ++q) {
      const std::size_t k = static_cast<std::size_t>(q);
      const Vec3 v = T.p[0] + r.s[k] * (T.p[1] - T.p[0]) + r.t[k] * (T.p[2] - T.p[0]);
      x.push_back(v.x);
      y.push_back(v.y);
      z.push_back(v.z);
      nx.push_back(T.n.x);
      ny.push_back(T.n.y);
      nz.push_back(T.n.z);
      w.push_back(2.0 * T.area * r.w[k]);
    }
    if (with_curls)
      for (int a = 0; a < part.count; ++a) {
        const Vec3 c = surface_curl(T, part.basis[a]);
        entries[0].emplace_back(part_index, part.position[a], c.x);
        entries[1].emplace_back(part_index, part.position[a], c.y);
        entries[2].emplace_back(part_index, part.position[a], c.z);
      }
    ++part_index;
  }
  if (with_curls)
    for (const auto& e : entries) {
      Eigen::SparseMatrix<double> C(part_index, dofs);
      C.setFromTriplets(e.begin(), e.end());
      curls.push_back(std::move(C));
    }
}

Eigen::MatrixXd sum_over_parts(const Eigen::Ref<const Eigen::MatrixXd>& A, Index per_part) {
  const Index parts = A.rows() / per_part;
  Eigen::MatrixXd out(parts, A.cols());
  for (Index j = 0; j < A.cols(); ++j) {
    const double* a = A.col(j).data();
    for (Index t = 0; t < parts; ++t) {
      double sum = 0.0;
      for (Index q = 0; q < per_part; ++q) sum += a[t * per_part + q];
      out(t, j) = sum;
    }
  }
  return out;
}

Eigen::Matrix<double, Eigen::Dynamic, 4> basis_values(const TriangleRule& rule) {
  Eigen::Matrix<double, Eigen::Dynamic, 4> L(rule.size(), 4);
  for (int q = 0; q < rule.size(); ++q) {
    const std::size_t k = static_cast<std::size_t>(q);
    L.row(q) << 1.0 - rule.s[k] - rule.t[k], rule.s[k], rule.t[k], 1.0;
  }
  return L;
}

void add_values_transpose_product(const std::vector<Part>& parts, const TriangleRule& rule,
                                  const Eigen::Ref<const Eigen::MatrixXd>& A, Eigen::Ref<Eigen::MatrixXd> out) {
  const Index n = rule.size();
  const Eigen::Matrix<double, Eigen::Dynamic, 4> L = basis_values(rule);
  const double *l0 = L.col(0).data(), *l1 = L.col(1).data(), *l2 = L.col(2).data();
  for (Index j = 0; j < A.cols(); ++j) {
    const double* a = A.col(j).data();
    double* o = out.col(j).data();
    for (std::size_t t = 0; t < parts.size(); ++t, a += n) {
      // the part's moments against the four basis values, in one pass over its points
      double m[4] = {0.0, 0.0, 0.0, 0.0};
      for (Index q = 0; q < n; ++q) {
        m[0] += l0[q] * a[q];
        m[1] += l1[q] * a[q];
        m[2] += l2[q] * a[q];
        m[3] += a[q];
      }
      const Part& part = parts[t];
      for (int d = 0; d < part.count; ++d) o[part.position[d]] += m[part.basis[d]];
    }
  }
}

FarPoints::FarPoints(const Vertices& points, const Index* I, Index m) {
  for (Index r = 0; r < m; ++r) {
    x.push_back(points(I[r], 0));
    y.push_back(points(I[r], 1));
    z.push_back(points(I[r], 2));
  }
  nx.assign(x.size(), 0.0);
  ny.assign(x.size(), 0.0);
  nz.assign(x.size(), 0.0);
  w.assign(x.size(), 1.0);
}

}  // namespace bem
