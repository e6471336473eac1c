# deal.II 9.4 exports its library target only through its own setup macros, and keeps include directories
# and definitions in variables, so wrap the release libraries in one imported target that carries all.
find_package(deal.II 9.4 REQUIRED HINTS ${DEAL_II_DIR} $ENV{DEAL_II_DIR})
if(NOT TARGET dealii::dealii)
  add_library(dealii::dealii INTERFACE IMPORTED)
  set_target_properties(dealii::dealii PROPERTIES
    INTERFACE_LINK_LIBRARIES "${DEAL_II_LIBRARIES_RELEASE}"
    INTERFACE_INCLUDE_DIRECTORIES "${DEAL_II_INCLUDE_DIRS}"
    INTERFACE_COMPILE_DEFINITIONS "${DEAL_II_USER_DEFINITIONS};${DEAL_II_USER_DEFINITIONS_RELEASE}")
endif()
