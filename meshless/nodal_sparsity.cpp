#include "meshless/nodal_sparsity.hpp"

#include <algorithm>
#include <stdexcept>

namespace meshless {

NodalSparsity::NodalSparsity(int num_nodes, const std::vector<const ShapeTable*>& tables,
                             const std::vector<const NodeIncidence*>& incidences) {
  if (tables.size() != incidences.size()) throw std::invalid_argument("NodalSparsity: one incidence per table");
  std::vector<std::vector<int>> rows(num_nodes);
#pragma omp parallel
  {
    std::vector<char> seen(num_nodes, 0);  // per-thread marker, reset after each row
#pragma omp for schedule(dynamic, 64)
    for (int i = 0; i < num_nodes; ++i) {
      std::vector<int>& row = rows[i];
      for (size_t t = 0; t < tables.size(); ++t) {
        const ShapeTable& table = *tables[t];
        const NodeIncidence& inc = *incidences[t];
        for (int e = inc.offsets[i]; e < inc.offsets[i + 1]; ++e) {
          const int q = inc.points[e];
          for (int s = table.begin(q); s < table.end(q); ++s) {
            const int j = table.nodes[s];
            if (!seen[j]) {
              seen[j] = 1;
              row.push_back(j);
            }
          }
        }
      }
      for (int j : row) seen[j] = 0;
      std::sort(row.begin(), row.end());
    }
  }
  row_offsets_.assign(num_nodes + 1, 0);
  for (int i = 0; i < num_nodes; ++i) row_offsets_[i + 1] = row_offsets_[i] + static_cast<int>(rows[i].size());
  columns_.resize(row_offsets_.back());
  for (int i = 0; i < num_nodes; ++i) std::copy(rows[i].begin(), rows[i].end(), columns_.begin() + row_offsets_[i]);
}

SparseMatrix NodalSparsity::make_matrix() const {
  const int n = num_nodes();
  const long long nnz = 9LL * static_cast<long long>(columns_.size());
  if (nnz > 2147483647LL) throw std::length_error("NodalSparsity: more than 2^31 non-zeros");
  SparseMatrix m(3 * n, 3 * n);
  m.resizeNonZeros(static_cast<Eigen::Index>(nnz));
  int* outer = m.outerIndexPtr();
  int* inner = m.innerIndexPtr();
  for (int i = 0; i < n; ++i) {
    const int len = row_length(i);
    for (int a = 0; a < 3; ++a) {
      const long long start = value_index(i, a, 0, 0);
      outer[3 * i + a] = static_cast<int>(start);
      for (int k = 0; k < len; ++k)
        for (int b = 0; b < 3; ++b) inner[start + 3 * k + b] = 3 * columns_[row_offsets_[i] + k] + b;
    }
  }
  outer[3 * n] = static_cast<int>(nnz);
  std::fill(m.valuePtr(), m.valuePtr() + nnz, 0.0);
  return m;
}

Eigen::SparseMatrix<double, Eigen::ColMajor, long> NodalSparsity::node_pattern() const {
  Eigen::SparseMatrix<double, Eigen::ColMajor, long> m(num_nodes(), num_nodes());
  m.resizeNonZeros(static_cast<Eigen::Index>(columns_.size()));
  std::copy(row_offsets_.begin(), row_offsets_.end(), m.outerIndexPtr());
  std::copy(columns_.begin(), columns_.end(), m.innerIndexPtr());
  std::fill(m.valuePtr(), m.valuePtr() + columns_.size(), 0.0);
  return m;
}

}  // namespace meshless
