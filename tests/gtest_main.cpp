// GoogleTest main() of the suites without MPI: OpenBLAS's kernels for this CPU first (core/openblas_kernel.hpp), so
// that a suite's factorisations run as fast as the tissue program's.
#include <gtest/gtest.h>

#include "core/openblas_kernel.hpp"

int main(int argc, char** argv) {
  core::use_supported_openblas_kernel(argv);  // may run the program again
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
