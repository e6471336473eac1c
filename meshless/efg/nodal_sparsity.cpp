#include "meshless/efg/nodal_sparsity.hpp"

#include <omp.h>

#include <algorithm>
#include <iterator>
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

long long NodalSparsity::add_pairs(const ShapeTable& table, const std::vector<int>& points, int* first_row) {
  const int n = num_nodes();
  // The given points of each node (a small incidence), then node by node: mark the row, and every node of those
  // points that is not marked is a missing pair. O(1) per pair tested.
  std::vector<int> offsets(n + 1, 0);
  for (int q : points)
    for (int s = table.begin(q); s < table.end(q); ++s) ++offsets[table.nodes[s] + 1];
  for (int i = 0; i < n; ++i) offsets[i + 1] += offsets[i];
  std::vector<int> point_of(offsets.back()), fill(offsets.begin(), offsets.end() - 1);
  for (int q : points)
    for (int s = table.begin(q); s < table.end(q); ++s) point_of[fill[table.nodes[s]]++] = q;

  std::vector<std::vector<std::pair<int, int>>> found(omp_get_max_threads());
#pragma omp parallel
  {
    std::vector<char> in_row(n, 0);
    std::vector<std::pair<int, int>>& mine = found[omp_get_thread_num()];
#pragma omp for schedule(dynamic, 64)
    for (int i = 0; i < n; ++i) {
      if (offsets[i] == offsets[i + 1]) continue;
      for (int k = row_offsets_[i]; k < row_offsets_[i + 1]; ++k) in_row[columns_[k]] = 1;
      for (int e = offsets[i]; e < offsets[i + 1]; ++e) {
        const int q = point_of[e];
        for (int s = table.begin(q); s < table.end(q); ++s) {
          const int j = table.nodes[s];
          if (in_row[j]) continue;
          in_row[j] = 1;  // report each missing pair of this row once
          mine.push_back({i, j});
        }
      }
      for (int k = row_offsets_[i]; k < row_offsets_[i + 1]; ++k) in_row[columns_[k]] = 0;
      for (auto m = mine.rbegin(); m != mine.rend() && m->first == i; ++m) in_row[m->second] = 0;
    }
  }
  std::vector<std::pair<int, int>> missing;
  for (const auto& f : found) missing.insert(missing.end(), f.begin(), f.end());
  if (missing.empty()) return 0;
  std::sort(missing.begin(), missing.end());

  // Merged in place, from the last row back to the first that gains a pair: a row moves up by the number of pairs
  // added before its end, so its new slots lie at or after its old ones, and a backward merge never overwrites an
  // entry it has still to read. The rows before the first new pair stay where they are. The capacity grows with
  // room to spare, so that later updates add their pairs without a copy.
  const std::size_t old_size = columns_.size();
  if (columns_.capacity() < old_size + missing.size()) columns_.reserve(old_size + missing.size() + old_size / 100);
  columns_.resize(old_size + missing.size());
  const int first = missing.front().first;
  std::vector<int> merged_offsets(row_offsets_);
  {
    auto next = missing.begin();
    int added = 0;
    for (int i = first; i < n; ++i) {
      for (; next != missing.end() && next->first == i; ++next) ++added;
      merged_offsets[i + 1] = row_offsets_[i + 1] + added;
    }
  }
  auto extra = missing.rbegin();
  for (int i = n - 1; i >= first; --i) {
    int from = row_offsets_[i + 1] - 1, to = merged_offsets[i + 1] - 1;
    for (; to >= merged_offsets[i]; --to) {
      const bool take_extra =
          extra != missing.rend() && extra->first == i && (from < row_offsets_[i] || extra->second > columns_[from]);
      columns_[to] = take_extra ? (extra++)->second : columns_[from--];
    }
  }
  row_offsets_ = std::move(merged_offsets);
  if (first_row) *first_row = std::min(*first_row, first);
  return static_cast<long long>(missing.size());
}

SparseMatrix NodalSparsity::make_matrix(double spare_fraction) const {
  const long long nnz = 9LL * static_cast<long long>(columns_.size());
  SparseMatrix m(3 * num_nodes(), 3 * num_nodes());
  m.data().reserve(static_cast<Eigen::Index>(std::min(2147483647.0, (1.0 + spare_fraction) * static_cast<double>(nnz))));
  refill_matrix(&m);
  return m;
}

void NodalSparsity::refill_matrix(SparseMatrix* matrix, int from_node) const {
  const int n = num_nodes();
  const long long nnz = 9LL * static_cast<long long>(columns_.size());
  if (nnz > 2147483647LL) throw std::length_error("NodalSparsity: more than 2^31 non-zeros");
  SparseMatrix& m = *matrix;
  if (from_node > 0 && m.rows() == 3 * n && m.cols() == 3 * n && m.isCompressed() &&
      m.data().allocatedSize() >= static_cast<Eigen::Index>(nnz)) {
    m.resizeNonZeros(static_cast<Eigen::Index>(nnz));  // within the allocation: the rows before from_node stay
  } else {
    from_node = 0;
    m.resize(3 * n, 3 * n);  // keeps the value and index arrays, empty
    m.resizeNonZeros(static_cast<Eigen::Index>(nnz));  // reallocates only when they are too small
  }
  int* outer = m.outerIndexPtr();
  int* inner = m.innerIndexPtr();
  double* values = m.valuePtr();
#pragma omp parallel for schedule(dynamic, 256)
  for (int i = from_node; i < n; ++i) {
    const int len = row_length(i);
    for (int a = 0; a < 3; ++a) {
      const long long start = value_index(i, a, 0, 0);
      outer[3 * i + a] = static_cast<int>(start);
      for (int k = 0; k < len; ++k)
        for (int b = 0; b < 3; ++b) inner[start + 3 * k + b] = 3 * columns_[row_offsets_[i] + k] + b;
      std::fill(values + start, values + start + 3 * len, 0.0);  // first touch on the thread that assembles the row
    }
  }
  outer[3 * n] = static_cast<int>(nnz);
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
