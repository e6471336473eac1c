// Which BLAS answers dgemm_ in a program linked like tissue (meshless, hence Ceres and PETSc). Debian's Ceres
// brings ATLAS's libf77blas into the link; when it comes first, ATLAS's generic build answers every dgemm_ and
// the sparse LUs run several times slower (CMakeLists.txt, docs/PERFORMANCE.md "BLAS"). The build removes it; this
// test fails if it comes back.
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <iostream>
#include <string>

#include "core/openblas_kernel.hpp"

extern "C" void dgemm_(const char*, const char*, const int*, const int*, const int*, const double*, const double*,
                       const int*, const double*, const int*, const double*, double*, const int*);

namespace {

TEST(Blas, DgemmIsNotAtlasGenericBuild) {
  Dl_info info{};
  ASSERT_NE(dladdr(reinterpret_cast<void*>(&dgemm_), &info), 0);
  ASSERT_NE(info.dli_fname, nullptr);
  const std::string loaded = info.dli_fname;
  const std::string resolved = std::filesystem::canonical(loaded).string();
  std::cout << "dgemm_ comes from " << loaded << " (" << resolved << ")\n";
  EXPECT_EQ(resolved.find("atlas"), std::string::npos) << resolved;
  EXPECT_EQ(resolved.find("f77blas"), std::string::npos) << resolved;
  // And it computes: C = A B for 2 x 2 matrices (column-major).
  const int n = 2;
  const double one = 1.0, zero = 0.0, a[] = {1, 3, 2, 4}, b[] = {5, 7, 6, 8};
  double c[4] = {};
  dgemm_("N", "N", &n, &n, &n, &one, a, &n, b, &n, &zero, c, &n);
  EXPECT_EQ(c[0], 19.0);
  EXPECT_EQ(c[1], 43.0);
  EXPECT_EQ(c[2], 22.0);
  EXPECT_EQ(c[3], 50.0);
}

// The suite's main() gives OpenBLAS the kernels this CPU supports (tests/gtest_main.cpp): its Prescott fallback,
// SSE3 only, ran dgemm_ 4x slower on a CPU with AVX-512 that OpenBLAS 0.3.21 did not recognise.
TEST(Blas, OpenBlasRunsTheKernelsThisCpuSupports) {
  const std::string kernels = core::openblas_core_name();
  if (kernels.empty()) GTEST_SKIP() << "dgemm_ is not OpenBLAS's here";
  std::cout << "OpenBLAS kernels: " << kernels << "; this CPU supports " << core::openblas_core_for_this_cpu() << "\n";
  if (!core::openblas_core_for_this_cpu().empty()) EXPECT_NE(kernels, "Prescott");
}

}  // namespace
