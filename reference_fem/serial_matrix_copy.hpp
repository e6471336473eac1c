#pragma once
// The tangent of a one-process solve is assembled into a deal.II SparseMatrix and its values are then written into
// the Trilinos matrix that the AMG and GMRES use, in place. Why: adding each cell's 30 x 30 block into an
// Epetra_CrsMatrix (global-to-local index maps and a search per entry, in WorkStream's serial copy stage) took about
// as long as computing the blocks; deal.II's own matrix adds a block row with one search, and one pass copies the
// values (docs/PERFORMANCE.md, "The FEM's assembly on one process").
//
// Lifetime: both matrices must keep the pattern they had at construction (their values may change); the Trilinos
// matrix must stay fill-completed (TrilinosWrappers::SparseMatrix::reinit with a pattern does that). Thread safety:
// copy() writes the target, so one thread at a time. One MPI process only.
#include <deal.II/lac/sparse_matrix.h>
#include <deal.II/lac/sparsity_pattern.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>

#include <vector>

namespace reference_fem {

class SerialMatrixCopy {
 public:
  /// Maps every entry of `pattern` (the deal.II pattern, diagonal first in each row) to its place in `target`'s rows.
  /// Throws std::invalid_argument when the two patterns differ or `target` is distributed over several processes.
  SerialMatrixCopy(const dealii::SparsityPattern& pattern, const dealii::TrilinosWrappers::SparseMatrix& target);

  /// target's values := from's values (entry by entry; from must be built on the constructor's pattern).
  void copy(const dealii::SparseMatrix<double>& from, dealii::TrilinosWrappers::SparseMatrix* target) const;

 private:
  std::vector<int> local_row_;  ///< per row of the pattern, its local row in the Epetra matrix
  std::vector<int> position_;   ///< per entry of the pattern (in its order), its index in that Epetra row's view
};

}  // namespace reference_fem
