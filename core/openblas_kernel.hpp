#pragma once
// Which of OpenBLAS's kernels the process runs, and the fix for a CPU it does not recognise.
//
// Every direct factorisation of both models (MUMPS for the EFG and LRPIM tangents, UMFPACK as the FEM's direct
// option) spends its time in dense front updates, i.e. in OpenBLAS's dgemm_ (docs/PERFORMANCE.md, "BLAS"). Debian
// 12's OpenBLAS (0.3.21, built with DYNAMIC_ARCH) picks its kernels when the library is loaded, from the CPU's model
// number. On an Intel CPU newer than its table (for example family 6, model 207) it falls back to its Prescott
// kernels, SSE3 only, instead of choosing by the CPU's features (OpenBLAS issue 4267, fixed in 0.3.25). On such a
// machine dgemm_ ran 4x slower than with the AVX-512 kernels the CPU supports (13.6 against 55.6 GFlop/s on
// 2,000 x 2,000, 2 threads), and so did every factorisation.
//
// OpenBLAS reads the environment variable OPENBLAS_CORETYPE only while it is being loaded, before main() runs.
// So the fix sets it and executes the program again, once, first thing in main().
//
// Thread safety: call use_supported_openblas_kernel() before any other thread, MPI or PETSc is started (it may
// replace the process). The queries are read-only and safe from any thread.
#include <string>

namespace core {

/// The name OpenBLAS gives its kernels in this process ("SkylakeX", "Haswell", "Prescott", ...); empty when
/// dgemm_ is not OpenBLAS's (another BLAS through Debian's alternatives).
std::string openblas_core_name();

/// The OPENBLAS_CORETYPE this CPU supports and OpenBLAS 0.3.21 has kernels for, by the CPU's features as the
/// compiler's runtime reports them (OS support for the wider registers included): "SkylakeX" with AVX-512
/// (F, CD, BW, DQ, VL), "Haswell" with AVX2 and FMA, "Sandybridge" with AVX; empty otherwise.
std::string openblas_core_for_this_cpu();

/// When OpenBLAS runs its Prescott fallback on a CPU that supports better kernels (openblas_core_for_this_cpu()),
/// sets OPENBLAS_CORETYPE to those and executes this program again with the same arguments (/proc/self/exe), so
/// that OpenBLAS loads them. Does nothing when OPENBLAS_CORETYPE is already set (the user's choice, or this
/// function's own earlier run: it never executes twice), when dgemm_ is not OpenBLAS's, or when OpenBLAS
/// recognised the CPU. Returns only when it did not execute again; if executing fails it says so on stderr and
/// the program continues with the slower kernels. `argv` is main()'s, terminated by a null pointer.
void use_supported_openblas_kernel(char** argv);

}  // namespace core
