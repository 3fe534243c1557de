# Finds the Debian-packaged dependencies and wraps the ones without a CMake config
# (GMP, MPFR) in imported targets.
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(nlohmann_json 3 REQUIRED)
find_package(CLI11 REQUIRED)
find_package(fmt REQUIRED)
find_package(OpenSSL REQUIRED)  # SHA-256 of the mesh in tree files
find_package(TBB REQUIRED)      # the CPU twin estimates a batch of boxes in parallel
find_package(CGAL REQUIRED)     # here, so that every directory sees CGAL::CGAL (exact/, tests/)

find_path(GMP_INCLUDE_DIR gmpxx.h REQUIRED)
find_library(GMP_LIBRARY gmp REQUIRED)
find_library(GMPXX_LIBRARY gmpxx REQUIRED)
find_library(MPFR_LIBRARY mpfr REQUIRED)
add_library(vobb::gmp INTERFACE IMPORTED)
target_include_directories(vobb::gmp INTERFACE ${GMP_INCLUDE_DIR})
target_link_libraries(vobb::gmp INTERFACE ${GMPXX_LIBRARY} ${GMP_LIBRARY})
add_library(vobb::mpfr INTERFACE IMPORTED)
target_link_libraries(vobb::mpfr INTERFACE ${MPFR_LIBRARY} vobb::gmp)

if(VOBB_WITH_ASSIMP)
  find_package(assimp REQUIRED)
endif()
