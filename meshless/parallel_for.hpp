#pragma once
// An OpenMP loop over indices whose body may throw. An exception must not leave an OpenMP region (the program
// would terminate), so each is caught where it happens; after the loop the one thrown at the lowest index is
// rethrown as it is (a SingularMomentMatrix or core::InadmissibleStrain keeps its data). The lowest index,
// not the first in time, so that a failure reads the same whatever order the threads ran in.
//
// Thread safety: body(i) runs concurrently for different i. It may write only to what belongs to i (a slot of
// a per-index array, not a bit of a std::vector<bool>: neighbouring bits share a word).
#include <exception>

namespace meshless {

/// Runs body(i) for i in [0, n) with OpenMP's dynamic schedule in chunks of `chunk` indices, then rethrows
/// the exception of the lowest index that threw, if any.
template <class Body>
void parallel_for(int n, int chunk, const Body& body) {
  std::exception_ptr error;
  int error_index = n;
#pragma omp parallel for schedule(dynamic, chunk)
  for (int i = 0; i < n; ++i) {
    try {
      body(i);
    } catch (...) {
#pragma omp critical(meshless_parallel_for_error)
      if (i < error_index) {
        error_index = i;
        error = std::current_exception();
      }
    }
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace meshless
