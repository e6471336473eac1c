#pragma once
// Sparse LU of the EFG tangent by MUMPS (a multifrontal solver: METIS nested-dissection ordering, dense BLAS-3
// kernels on the fronts), on one process.
//
// Why MUMPS and not UMFPACK: the EFG rows couple hundreds of nodes (d_max = 2: ~270 per node), so the factors
// are a large fraction of dense and the factorisation is all dense front work. On the lung_small tangent at the
// shipped resolution (27,900 unknowns, 22.8 M entries) MUMPS factorises in 32.4 s against UMFPACK's 55.9 s, with
// half its memory: its nested dissection makes fewer, larger fronts that run near the BLAS's peak
// (docs/MESHLESS.md §2, measured by bench_efg's BM_EfgDirectLung).
//
// Lifetime: nothing passed in is referenced after a call returns (the matrix is copied into MUMPS's coordinate
// arrays). Thread safety: an instance is used from one thread at a time. Instances in different threads (the
// surrogate's parallel training) are safe but take turns: MUMPS keeps Fortran module state during a call, so every
// MUMPS call in the process holds one lock. Each factorisation uses all cores through the BLAS anyway. MPI must be initialised before construction (every tissue program and MPI test main does, through
// dealii::Utilities::MPI::MPI_InitFinalize): MUMPS runs on MPI_COMM_SELF.
#include <Eigen/Core>
#include <memory>
#include <string>

#include "meshless/efg/nodal_sparsity.hpp"

namespace meshless {

class MumpsLu {
 public:
  /// `name` labels error messages (the problem). `low_rank_tolerance` > 0 turns on MUMPS's block low-rank (BLR)
  /// factorisation (ICNTL(35) = 2) with this dropping parameter (CNTL(7), applied to the scaled matrix): the off-
  /// diagonal blocks of each front are compressed to that accuracy, so the factors are approximate and solve() is
  /// accurate to about this tolerance times the condition number. 0 (the default) is the exact LU. Throws
  /// std::logic_error when MPI is not initialised, std::invalid_argument for a negative tolerance.
  ///
  /// `symmetric_part`: factorise (A + A^T) / 2 by LDL^T with pivoting (MUMPS SYM = 2) instead of A by LU, about half
  /// the operations and the factors' memory. solve() then solves with the symmetric part: an approximate inverse of
  /// a nearly symmetric A (the EFG tangent: VCI's test-gradient correction and, at k != 0, the law's tangent are its
  /// only unsymmetric parts) that Newton's own test corrects, as it corrects kept factors of an older tangent. A's
  /// pattern must be structurally symmetric (the EFG's node pairs are).
  ///
  /// `block_size`: the unknowns come in consecutive groups of this size, and the pattern holds a dense block for each
  /// pair of groups it couples (a meshless model's three displacement components per node, NodalSparsity). MUMPS's
  /// analysis then orders the graph of the groups (ICNTL(15) = -block_size) instead of that of the unknowns: on
  /// lung_small's EFG tangent its nested dissection needs 19 % fewer operations (docs/PERFORMANCE.md, "MUMPS orders
  /// the node graph"). The factors are those of the same matrix in another order. 1 (the default): no groups. The
  /// matrix order must be a multiple of it (std::invalid_argument from factorise() otherwise); < 1 is refused here.
  explicit MumpsLu(std::string name, double low_rank_tolerance = 0.0, bool symmetric_part = false,
                   int block_size = 1);
  ~MumpsLu();
  MumpsLu(const MumpsLu&) = delete;
  MumpsLu& operator=(const MumpsLu&) = delete;

  /// LU factors of `a` (square; compressed or not). The first call orders the pattern (METIS) and later calls
  /// reuse that analysis: every matrix given to one instance must have the pattern of the first (the model
  /// makes a new solver when a cut adds node pairs). Throws std::runtime_error naming the cause when MUMPS
  /// fails (numerically singular matrix, out of memory), std::invalid_argument when the pattern changed.
  void factorise(const SparseMatrix& a);
  /// x with A x = b for the last factorised A.
  Eigen::VectorXd solve(const Eigen::VectorXd& b);

  /// Entries of the LU factors of the last factorisation (MUMPS INFOG(29)) and its floating-point operations
  /// (RINFOG(3)); 0 before the first.
  double factor_entries() const { return factor_entries_; }
  double factorisation_flops() const { return factorisation_flops_; }

 private:
  /// The values (a_ij + a_ji) / 2 of the upper triangle and the diagonal, in the analysed order, and with `first`
  /// their coordinates. Throws std::invalid_argument when an entry has no transposed entry.
  void fill_symmetric_part(const SparseMatrix& a, bool first);

  struct Mumps;
  std::unique_ptr<Mumps> mumps_;
  std::string name_;
  bool symmetric_part_ = false;
  int block_size_ = 1;
  Eigen::Index analysed_entries_ = 0;  // a.nonZeros() of the analysed pattern (symmetric_part)
  double factor_entries_ = 0.0, factorisation_flops_ = 0.0;
};

}  // namespace meshless
