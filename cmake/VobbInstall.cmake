# `cmake --install BUILD --prefix P` installs vobb for other CMake projects:
#   P/bin/vobb, P/bin/vobb-make-analytic
#   P/include/vobb/{common,exact,fast,validate,data}/*.h, included as "common/mesh.h"
#   P/lib/libvobb_*.a and P/lib/cmake/vobb/: find_package(vobb) gives vobb::common,
#   vobb::meshio, vobb::exact, vobb::fast, vobb::fast_poly, vobb::fast_gl, vobb::png, vobb::analytic,
#   vobb::validate and vobb::collision (link what you use; each brings what it needs).
# The libraries are static, so their private dependencies (CGAL, TBB, EGL, ODE, FCL, ...) are
# found again by vobbConfig.cmake. tests/install/ builds a project against an installed tree.
include(CMakePackageConfigHelpers)

set(VOBB_EXPORTED vobb_common vobb_meshio vobb_png vobb_analytic vobb_exact vobb_fast vobb_fast_poly
    vobb_fast_gl vobb_validate vobb_collision)
# Interface targets the libraries link privately: exported too, since a static library's
# private links are its users' links.
set(VOBB_EXPORTED_HELPERS vobb_cgal vobb_config)
foreach(t IN LISTS VOBB_EXPORTED VOBB_EXPORTED_HELPERS)
  string(REGEX REPLACE "^vobb_" "" name ${t})
  set_target_properties(${t} PROPERTIES EXPORT_NAME ${name})
endforeach()

install(TARGETS ${VOBB_EXPORTED} ${VOBB_EXPORTED_HELPERS} EXPORT vobbTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(TARGETS vobb vobb-make-analytic RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
foreach(dir common exact fast validate data)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${dir}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/vobb/${dir}
          FILES_MATCHING PATTERN "*.h" PATTERN "real" EXCLUDE)
endforeach()
install(FILES ${PROJECT_BINARY_DIR}/generated/vobb/config.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/vobb/vobb)

set(VOBB_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/vobb)
install(EXPORT vobbTargets NAMESPACE vobb:: DESTINATION ${VOBB_CMAKE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/vobbConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/vobbConfig.cmake INSTALL_DESTINATION ${VOBB_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/vobbConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/vobbConfig.cmake ${PROJECT_BINARY_DIR}/vobbConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/VobbGmp.cmake
        DESTINATION ${VOBB_CMAKE_DIR})
