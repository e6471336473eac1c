#include "meshless/direct_solver_estimate.hpp"

#include <fmt/format.h>
#include <umfpack.h>
#include <unistd.h>

#include <stdexcept>
#include <type_traits>

namespace meshless {

static_assert(std::is_same_v<SuiteSparse_long, UmfpackMatrix::StorageIndex>,
              "UmfpackMatrix must use SuiteSparse_long indices so that Eigen calls UMFPACK's dl routines");

DirectSolverEstimate estimate_direct_solver(const UmfpackMatrix& pattern) {
  if (!pattern.isCompressed()) throw std::invalid_argument("estimate_direct_solver: the matrix must be compressed");
  double control[UMFPACK_CONTROL], info[UMFPACK_INFO];
  umfpack_dl_defaults(control);
  void* symbolic = nullptr;
  // Ax may be null: the symbolic analysis then orders by the pattern alone.
  const SuiteSparse_long status =
      umfpack_dl_symbolic(pattern.rows(), pattern.cols(), pattern.outerIndexPtr(), pattern.innerIndexPtr(), nullptr,
                          &symbolic, control, info);
  if (symbolic) umfpack_dl_free_symbolic(&symbolic);
  if (status != UMFPACK_OK)
    throw std::runtime_error(fmt::format("UMFPACK symbolic analysis failed (status {})", status));
  const double unit = info[UMFPACK_SIZE_OF_UNIT];
  DirectSolverEstimate e;
  e.peak_memory_bytes = info[UMFPACK_PEAK_MEMORY_ESTIMATE] * unit;
  e.factor_bytes = info[UMFPACK_NUMERIC_SIZE_ESTIMATE] * unit;
  e.factorisation_flops = info[UMFPACK_FLOPS_ESTIMATE];
  return e;
}

DirectSolverEstimate estimate_direct_solver_blocked(const UmfpackMatrix& block_pattern, int block_size) {
  DirectSolverEstimate e = estimate_direct_solver(block_pattern);
  const double b = block_size;
  e.peak_memory_bytes *= b * b;
  e.factor_bytes *= b * b;
  e.factorisation_flops *= b * b * b;
  return e;
}

double physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page_size = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page_size > 0 ? static_cast<double>(pages) * static_cast<double>(page_size) : 0.0;
}

}  // namespace meshless
