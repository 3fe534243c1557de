# GMP (with gmpxx) and MPFR have no CMake config on Debian: imported targets vobb::gmp and
# vobb::mpfr wrap them. Included by VobbDeps.cmake, and by an installed vobbConfig.cmake, so a
# project that links the installed libraries finds the same libraries the same way.
if(NOT TARGET vobb::gmp)
  find_path(GMP_INCLUDE_DIR gmpxx.h REQUIRED)
  find_library(GMP_LIBRARY gmp REQUIRED)
  find_library(GMPXX_LIBRARY gmpxx REQUIRED)
  add_library(vobb::gmp INTERFACE IMPORTED)
  target_include_directories(vobb::gmp INTERFACE ${GMP_INCLUDE_DIR})
  target_link_libraries(vobb::gmp INTERFACE ${GMPXX_LIBRARY} ${GMP_LIBRARY})
endif()
if(NOT TARGET vobb::mpfr)
  find_library(MPFR_LIBRARY mpfr REQUIRED)
  add_library(vobb::mpfr INTERFACE IMPORTED)
  target_link_libraries(vobb::mpfr INTERFACE ${MPFR_LIBRARY} vobb::gmp)
endif()
