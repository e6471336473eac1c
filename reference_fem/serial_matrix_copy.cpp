#include "reference_fem/serial_matrix_copy.hpp"

#include <Epetra_CrsMatrix.h>
#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace reference_fem {

using namespace dealii;

SerialMatrixCopy::SerialMatrixCopy(const SparsityPattern& pattern, const TrilinosWrappers::SparseMatrix& target) {
  const Epetra_CrsMatrix& m = target.trilinos_matrix();
  if (m.Comm().NumProc() != 1)
    throw std::invalid_argument("SerialMatrixCopy: the Trilinos matrix is distributed over several processes");
  if (!m.Filled()) throw std::invalid_argument("SerialMatrixCopy: the Trilinos matrix is not fill-completed");
  const auto rows = static_cast<int>(pattern.n_rows());
  if (m.NumMyRows() != rows || static_cast<std::size_t>(m.NumMyNonzeros()) != pattern.n_nonzero_elements())
    throw std::invalid_argument(fmt::format("SerialMatrixCopy: the patterns differ ({} rows and {} entries against {} "
                                            "and {})",
                                            rows, pattern.n_nonzero_elements(), m.NumMyRows(), m.NumMyNonzeros()));
  local_row_.resize(rows);
  position_.resize(pattern.n_nonzero_elements());
  std::vector<std::pair<int, int>> columns;  // (global column, position in the Epetra row), sorted by column
  std::size_t entry = 0;
  for (int r = 0; r < rows; ++r) {
    const int local = m.RowMap().LID(r);
    int n = 0;
    double* values = nullptr;
    int* indices = nullptr;
    if (local < 0 || m.ExtractMyRowView(local, n, values, indices) != 0 ||
        static_cast<std::size_t>(n) != pattern.row_length(r))
      throw std::invalid_argument(fmt::format("SerialMatrixCopy: row {} differs between the patterns", r));
    local_row_[r] = local;
    columns.resize(n);
    for (int k = 0; k < n; ++k) columns[k] = {m.ColMap().GID(indices[k]), k};
    std::sort(columns.begin(), columns.end());
    for (auto it = pattern.begin(r); it != pattern.end(r); ++it, ++entry) {
      const int column = static_cast<int>(it->column());
      const auto found = std::lower_bound(columns.begin(), columns.end(), std::make_pair(column, -1));
      if (found == columns.end() || found->first != column)
        throw std::invalid_argument(fmt::format("SerialMatrixCopy: ({}, {}) is not in the Trilinos pattern", r, column));
      position_[entry] = found->second;
    }
  }
}

void SerialMatrixCopy::copy(const SparseMatrix<double>& from, TrilinosWrappers::SparseMatrix* target) const {
  const Epetra_CrsMatrix& m = target->trilinos_matrix();
  std::size_t entry = 0;
  for (std::size_t r = 0; r < local_row_.size(); ++r) {
    int n = 0;
    double* values = nullptr;
    int* indices = nullptr;
    m.ExtractMyRowView(local_row_[r], n, values, indices);  // a view of the values: written in place
    for (auto it = from.begin(r); it != from.end(r); ++it, ++entry) values[position_[entry]] = it->value();
  }
}

}  // namespace reference_fem
