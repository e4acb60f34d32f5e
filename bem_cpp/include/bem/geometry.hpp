#pragma once
// Closed polygon Gamma (docs/method.md sections 2 and 9): panels, outward normals,
// validation of the input nodes, and location of points relative to Gamma.
#include <Eigen/Dense>
#include <cmath>
#include <vector>

namespace bem {

/// Dense matrix at the binding boundary (row-major so numpy arrays map without copies).
using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
/// (n, 2) array of points, row-major.
using Points = Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>;
using Vector = Eigen::VectorXd;
using Index = Eigen::Index;

/// Plain 2-vector for the hot loops (no alignment or expression-template overhead).
struct Vec2 {
  double x, y;
};
inline Vec2 operator+(Vec2 a, Vec2 b) { return {a.x + b.x, a.y + b.y}; }
inline Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
inline Vec2 operator*(double s, Vec2 a) { return {s * a.x, s * a.y}; }
inline double dot(Vec2 a, Vec2 b) { return a.x * b.x + a.y * b.y; }
/// z-component of the cross product a x b.
inline double cross(Vec2 a, Vec2 b) { return a.x * b.y - a.y * b.x; }
inline double norm(Vec2 a) { return std::sqrt(a.x * a.x + a.y * a.y); }
/// Rotation by -90 degrees: for a unit tangent t of a counter-clockwise panel this is
/// the outward normal (t_y, -t_x).
inline Vec2 rotate_cw(Vec2 t) { return {t.y, -t.x}; }

/// Straight panel a -> b with length h, unit tangent t = (b - a)/h, outward normal
/// n = (t_y, -t_x) (outward for a counter-clockwise polygon) and midpoint m.
struct Panel {
  Vec2 a, b, t, n, m;
  double h;
};

Panel make_panel(Vec2 a, Vec2 b);

/// Euclidean distance from the point z to the segment of panel p.
double distance(const Panel& p, Vec2 z);
/// Euclidean distance between the segments of two panels (0 if they intersect).
double distance(const Panel& p, const Panel& q);

/// A validated closed polygon: node j -> node j+1 (mod n) is panel j.
///
/// The constructor throws std::invalid_argument (ValueError in Python) with a
/// one-line message if the nodes do not describe a simple counter-clockwise polygon:
/// fewer than 3 nodes, non-finite coordinates, repeated consecutive nodes (also
/// last == first), a panel folding back onto its predecessor, self-intersection
/// (all pairs of non-adjacent panels are checked, O(n log n + k) by a sweep over x),
/// or clockwise orientation (non-positive signed area).
class Polygon {
 public:
  explicit Polygon(const Eigen::Ref<const Points>& nodes);

  Index size() const { return static_cast<Index>(panels_.size()); }
  const Panel& panel(Index j) const { return panels_[static_cast<std::size_t>(j)]; }
  const std::vector<Panel>& panels() const { return panels_; }
  /// Panel lengths h_j.
  Vector lengths() const;
  /// Diagonal of the bounding box (an upper bound of diam(Omega) within sqrt(2)).
  double bounding_diameter() const { return bbox_diameter_; }
  /// Signed (shoelace) area, positive for counter-clockwise nodes.
  double signed_area() const { return area_; }

 private:
  std::vector<Panel> panels_;
  double bbox_diameter_ = 0.0;
  double area_ = 0.0;
};

/// Calls f(i) for every panel i of a closed polygon with n panels, in parallel, such that
/// panels processed at the same time never share a node: even panels, then odd panels, then
/// the last panel if n is odd (it shares node 0 with panel 0). f(i) may then write the rows
/// of the nodes i and i + 1 freely (the assemblies over panel pairs; dynamic scheduling
/// balances panels that carry different numbers of pairs).
template <class F>
void for_each_panel_coloured(Index n, F&& f) {
  const Index half = n / 2;
#pragma omp parallel
  {
#pragma omp for schedule(dynamic, 1)
    for (Index k = 0; k < half; ++k) f(2 * k);
#pragma omp for schedule(dynamic, 1)
    for (Index k = 0; k < half; ++k) f(2 * k + 1);
#pragma omp single
    if (n % 2 == 1) f(n - 1);
  }
}

enum class Location { Exterior, OnBoundary, Interior };

/// Location of z relative to Gamma. Points closer than `on_tolerance` to Gamma are
/// OnBoundary; otherwise the even-odd crossing rule decides Interior/Exterior.
Location locate(const Polygon& polygon, Vec2 z, double on_tolerance);

}  // namespace bem
