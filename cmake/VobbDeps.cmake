# Finds the Debian-packaged dependencies and wraps the ones without a CMake config
# (GMP, MPFR) in imported targets.
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(nlohmann_json 3 REQUIRED)
find_package(CLI11 REQUIRED)
find_package(fmt REQUIRED)
find_package(OpenSSL REQUIRED)  # SHA-256 of the mesh in tree files
find_package(TBB REQUIRED)      # the CPU twin estimates a batch of boxes in parallel
find_package(CGAL REQUIRED)     # here, so that every directory sees CGAL::CGAL (exact/, tests/)

include(VobbGmp)  # vobb::gmp, vobb::mpfr (also what an installed vobbConfig.cmake uses)

if(VOBB_WITH_ASSIMP)
  find_package(assimp REQUIRED)
endif()
