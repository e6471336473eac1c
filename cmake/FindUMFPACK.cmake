# FindUMFPACK
# -----------
# Debian's libsuitesparse-dev ships UMFPACK and AMD without a CMake package configuration, so this module
# locates them and provides the imported targets UMFPACK::UMFPACK (used through Eigen's UmfPackSupport) and
# UMFPACK::AMD (the fill-reducing ordering, used on its own to estimate a factorisation's cost).
find_path(UMFPACK_INCLUDE_DIR NAMES umfpack.h PATH_SUFFIXES suitesparse)
find_library(UMFPACK_LIBRARY NAMES umfpack)
find_library(UMFPACK_AMD_LIBRARY NAMES amd)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(UMFPACK REQUIRED_VARS UMFPACK_LIBRARY UMFPACK_AMD_LIBRARY UMFPACK_INCLUDE_DIR)
if(UMFPACK_FOUND AND NOT TARGET UMFPACK::UMFPACK)
  add_library(UMFPACK::UMFPACK UNKNOWN IMPORTED)
  set_target_properties(UMFPACK::UMFPACK PROPERTIES
    IMPORTED_LOCATION "${UMFPACK_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${UMFPACK_INCLUDE_DIR}")
  add_library(UMFPACK::AMD UNKNOWN IMPORTED)
  set_target_properties(UMFPACK::AMD PROPERTIES
    IMPORTED_LOCATION "${UMFPACK_AMD_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${UMFPACK_INCLUDE_DIR}")
endif()
mark_as_advanced(UMFPACK_INCLUDE_DIR UMFPACK_LIBRARY UMFPACK_AMD_LIBRARY)
