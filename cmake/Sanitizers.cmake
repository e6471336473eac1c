# Sanitizer and fuzzing builds (README.md, "Sanitizers and fuzzing"). Each goes into its own build folder.
#
#   TISSUE_SANITIZE=ON  everything (libraries, tissue, tests) with AddressSanitizer + UndefinedBehaviorSanitizer;
#                       run the unit suites with `ctest -L unit`.
#   TISSUE_FUZZ=ON      Clang only: core with ASan + UBSan + libFuzzer coverage, and the libFuzzer targets of
#                       tests/fuzz with one ctest each (label `fuzz`), TISSUE_FUZZ_SECONDS long. Nothing else is
#                       built in that folder.
option(TISSUE_SANITIZE "Build everything with AddressSanitizer and UndefinedBehaviorSanitizer" OFF)
option(TISSUE_FUZZ "Build core and the libFuzzer targets of tests/fuzz (Clang; implies the sanitizers)" OFF)
set(TISSUE_FUZZ_SECONDS 60 CACHE STRING "Time budget of each fuzzing ctest [s]")

if(TISSUE_FUZZ AND NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
  message(FATAL_ERROR "TISSUE_FUZZ needs Clang's libFuzzer: configure with -DCMAKE_CXX_COMPILER=clang++ "
                      "(Debian 12: packages clang and libclang-rt-14-dev)")
endif()

if(TISSUE_SANITIZE OR TISSUE_FUZZ)
  # Stop at the first UB report (so a test or the fuzzer fails) and keep frames for readable stacks.
  set(tissue_sanitizers -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  add_compile_options(${tissue_sanitizers} -g)
  add_link_options(-fsanitize=address,undefined)
  # Eigen switches to its own offset ("handmade") aligned malloc when __SANITIZE_ADDRESS__ is defined, while
  # Debian's libgmsh uses Eigen with plain malloc/free. Template instances such as
  # ColPivHouseholderQR<MatrixXd>'s constructor are weak symbols, so the dynamic linker binds libgmsh's calls
  # to our sanitized copy: fullMatrix<double>::luSolve (Gmsh's 2-D frontal mesher) then allocated through
  # our copy and freed with its own inlined std::free, 16 bytes inside the block, and ASan aborted with
  # "bad-free". Keeping Eigen's allocation the same as libgmsh's removes that clash; ASan's malloc returns
  # 16-byte aligned blocks on x86-64, which Eigen asserts.
  add_compile_definitions(EIGEN_MALLOC_ALREADY_ALIGNED=1)
endif()
if(TISSUE_FUZZ)
  # Coverage instrumentation for libFuzzer in every library; the fuzz targets link the fuzzer's main().
  add_compile_options(-fsanitize=fuzzer-no-link)
endif()
