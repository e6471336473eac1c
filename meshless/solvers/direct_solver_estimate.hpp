#pragma once
// Will a sparse LU of this matrix fit in memory? A fill-reducing ordering and its elimination tree (no
// numerical work) predict the peak memory, the size of the LU factors and the flop count. The EFG model uses
// the blocked AMD estimate to choose between the direct solver and the iterative fallback from the actual
// sparsity pattern, rather than from a fixed DOF threshold: EFG rows hold hundreds of entries, so the fill-in
// depends on the support size as much as on the node count. UMFPACK's full symbolic analysis is the
// reference the blocked estimate is tested against.
#include <Eigen/SparseCore>

namespace meshless {

/// The matrix type handed to UMFPACK: 64-bit indices select its "dl" routines. The "di" (int) routines fail
/// with "out of memory" on EFG systems of about 8k nodes (6 GB of factors), far below the machine's RAM.
/// (`long` is SuiteSparse_long on Linux; the .cpp checks it.)
using UmfpackMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, long>;

struct DirectSolverEstimate {
  double peak_memory_bytes = 0.0;   ///< during the factorisation: factors, matrix and work arrays
  double factor_bytes = 0.0;        ///< the L and U factors
  double factorisation_flops = 0.0; ///< floating-point operations of the numerical factorisation
};

/// Symbolic analysis of `pattern` (values ignored) with UMFPACK's default controls, the same ones
/// Eigen::UmfPackLU uses. Throws std::runtime_error when UMFPACK rejects the pattern.
DirectSolverEstimate estimate_direct_solver(const UmfpackMatrix& pattern);

/// The estimate for a matrix of dense `block_size` x `block_size` blocks (3 x 3 per EFG node pair) with a
/// symmetric pattern, from AMD's analysis of the pattern of its blocks: block_size^2 fewer entries, and AMD
/// alone instead of UMFPACK's whole symbolic analysis (seconds instead of two minutes on a 32k-node cloud).
/// Each entry of the block factors is a dense block: memory scales by block_size^2 and flops by
/// block_size^3. tests/test_efg_linear_solvers.cpp compares it with UMFPACK's full analysis.
DirectSolverEstimate estimate_direct_solver_blocked(const UmfpackMatrix& block_pattern, int block_size);

}  // namespace meshless
