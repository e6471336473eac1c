#include "core/openblas_kernel.hpp"

#include <dlfcn.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <iostream>

namespace core {

std::string openblas_core_name() {
  // Looked up, not linked: core does not link a BLAS, and a program whose BLAS is not OpenBLAS has no such symbol.
  using CoreName = char* (*)();
  const auto name = reinterpret_cast<CoreName>(dlsym(RTLD_DEFAULT, "openblas_get_corename"));
  if (name == nullptr) return {};
  const char* core = name();
  return core != nullptr ? std::string(core) : std::string();
}

std::string openblas_core_for_this_cpu() {
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") && __builtin_cpu_supports("avx512bw") &&
      __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl"))
    return "SkylakeX";
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return "Haswell";
  if (__builtin_cpu_supports("avx")) return "Sandybridge";
  return {};
}

void use_supported_openblas_kernel(char** argv) {
  if (std::getenv("OPENBLAS_CORETYPE") != nullptr) return;
  if (openblas_core_name() != "Prescott") return;  // not OpenBLAS, or it recognised the CPU
  const std::string supported = openblas_core_for_this_cpu();
  if (supported.empty()) return;  // Prescott is what this CPU runs
  if (setenv("OPENBLAS_CORETYPE", supported.c_str(), 1) != 0) return;
  execv("/proc/self/exe", argv);
  // Only reached when executing failed: keep going on the slower kernels, and say so.
  std::cerr << "warning: OpenBLAS runs its generic Prescott kernels on this CPU, which supports its " << supported
            << " kernels; executing this program again with OPENBLAS_CORETYPE=" << supported
            << " failed (" << std::strerror(errno) << "). Factorisations will be several times slower; set "
            << "OPENBLAS_CORETYPE=" << supported << " in the environment to avoid this.\n";
}

}  // namespace core
