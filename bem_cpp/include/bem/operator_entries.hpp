#pragma once
// Entries of the Galerkin matrices V_h and K_h (operators.hpp) on arbitrary index sets,
// for the H-matrix assembly (hmatrix.hpp): a row, a column or a dense block at a time.
// The panel-pair integrals are those of the dense assembly (log_integrals.hpp: closed
// forms near, Gauss rules far, far pairs of one test panel in vector batches), so a
// near-field block equals the dense one up to round-off.
//
// A dof is a sum of two panel shape functions: P1 hat of node i = phi_1 on panel i - 1 +
// phi_0 on panel i; P0 indicator of panel i = phi_0 + phi_1 on panel i.
#include <memory>
#include <vector>

#include "bem/far_field.hpp"
#include "bem/geometry.hpp"
#include "bem/hmatrix.hpp"
#include "bem/operators.hpp"

namespace bem {

enum class Kernel {
  SingleLayer,  ///< V_h, rows and columns in the same space
  DoubleLayer,  ///< K_h, rows in the flux space, columns P1
};

/// The dofs of one side of a block, prepared once: their panels (sorted, unique, also as
/// PanelArrays for the vector batches) and, per dof, the positions and shapes of its terms.
struct DofSet {
  std::vector<Index> panels;
  std::vector<Index> position;  ///< 2 per dof: index into panels
  std::vector<int> shape;       ///< 2 per dof
  PanelArrays arrays;
  Index size() const { return static_cast<Index>(position.size() / 2); }
};

class OperatorEntries : public EntrySource {
 public:
  /// Throws std::invalid_argument for V with rows != cols or K with P0 columns. The
  /// polygon must outlive the object.
  OperatorEntries(const Polygon& polygon, Kernel kernel, Space rows, Space cols);

  Index size() const { return polygon_.size(); }

  /// out[r + c ld] = A(I[r], J[c]) for r < m, c < k (column-major, leading dimension ld).
  /// Thread-safe.
  void block(const Index* I, Index m, const Index* J, Index k, double* out, Index ld) const;
  /// The same on prepared dof sets.
  void block(const DofSet& rows, const DofSet& cols, double* out, Index ld) const;
  DofSet dofs(Space space, const Index* dofs, Index m) const;
  /// The same into d, reusing its storage.
  void dofs_into(Space space, const Index* dofs, Index m, DofSet& d) const;
  /// EntrySource: rows and columns of I x J with both sides prepared once.
  std::unique_ptr<EntryBlock> block(const Index* I, Index m, const Index* J, Index k) const override;
  Space row_space() const { return rows_; }
  Space col_space() const { return cols_; }

 private:
  const Polygon& polygon_;
  Kernel kernel_;
  Space rows_, cols_;
};

}  // namespace bem
