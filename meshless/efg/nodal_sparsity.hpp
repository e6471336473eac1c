#pragma once
// Sparsity of the EFG system matrix of eq. 20: node i couples to node j when some integration point lies in
// both supports. Each coupled node pair is a dense 3x3 block, so the pattern is built once per node pair and
// expanded to degrees of freedom (3i + a, 3j + b). Assembly then writes straight into the CSR value array
// instead of going through triplets (a 32k-node cloud would need ~10^10 triplets).
#include <Eigen/SparseCore>
#include <vector>

#include "meshless/efg/integration_points.hpp"

namespace meshless {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

class NodalSparsity {
 public:
  /// @param tables the integration-point tables whose node pairs couple (volume, boundary)
  NodalSparsity(int num_nodes, const std::vector<const ShapeTable*>& tables,
                const std::vector<const NodeIncidence*>& incidences);

  int num_nodes() const { return static_cast<int>(row_offsets_.size()) - 1; }
  /// Coupled nodes of node i, ascending: columns_[row_offsets_[i] .. row_offsets_[i+1]).
  int row_begin(int i) const { return row_offsets_[i]; }
  int row_end(int i) const { return row_offsets_[i + 1]; }
  int row_length(int i) const { return row_offsets_[i + 1] - row_offsets_[i]; }
  int column(int k) const { return columns_[k]; }
  long long num_block_entries() const { return static_cast<long long>(columns_.size()); }

  /// Add to this pattern every node pair that shares one of `points` (rows of `table`) and is not in it yet;
  /// returns how many block entries were added (both (i, j) and (j, i) count). A cut that advances mostly
  /// removes couplings, so the local update keeps the pattern of the shorter cut and adds the few pairs that
  /// only the new points couple (a cell split differently, a new lip point); the pairs in excess are assembled
  /// as zeros. The rows are merged in place (the rows before the first that gains a pair do not move); when
  /// first_row is not null it is lowered to that row, if any pair was added.
  long long add_pairs(const ShapeTable& table, const std::vector<int>& points, int* first_row = nullptr);

  /// A 3N by 3N row-major matrix with this pattern and zero values, with its value and index arrays allocated
  /// for spare_fraction more entries (room for add_pairs(), filled by refill_matrix() without a new allocation).
  SparseMatrix make_matrix(double spare_fraction = 0.0) const;
  /// Give `m` this pattern and zero values, in its own arrays when they have room (else they are reallocated).
  /// With from_node > 0, `m` already holds this pattern's rows of the nodes before from_node (the pattern changed
  /// only from there on, add_pairs' first_row): when its arrays have room, only the later rows are written (zero
  /// values), and the earlier ones keep their values; otherwise the whole matrix is refilled.
  void refill_matrix(SparseMatrix* m, int from_node = 0) const;
  /// The N by N node-pair pattern as a compressed column-major matrix with 64-bit indices (values zero):
  /// what an ordering analyses instead of the 9x larger DOF pattern. The pattern is symmetric, so the CSR
  /// arrays serve as CSC arrays.
  Eigen::SparseMatrix<double, Eigen::ColMajor, long> node_pattern() const;

  /// Index into the value array of entry (3i + a, 3 * column(row_begin(i) + k) + b).
  long long value_index(int i, int a, int k, int b) const {
    return 9LL * row_offsets_[i] + 3LL * a * row_length(i) + 3LL * k + b;
  }

 private:
  std::vector<int> row_offsets_;  // #nodes + 1 (in node blocks)
  std::vector<int> columns_;      // node columns
};

}  // namespace meshless
