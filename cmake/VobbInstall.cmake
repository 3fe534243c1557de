# `cmake --install BUILD --prefix P` installs vobb for other CMake projects:
#   P/bin/vobb, P/bin/vobb-make-analytic
#   P/include/vobb/vobb.h, gl.h, config.h: the public face; P/include/vobb/detail/...: what it
#     includes (internal: common/, exact/, fast/, builder/, collision/, validate/collision/)
#   P/lib/libvobb_*.a and P/lib/cmake/vobb/: find_package(vobb [COMPONENTS GL collision assimp])
#     gives vobb::vobb, the core: load a solid, build, certify, estimate on the CPU, compare.
#     Its dependencies: CGAL, Eigen, GMP, MPFR, TBB and OpenSSL's libcrypto (SHA-256).
#     Components, each found only when asked for: GL -> vobb::gl (<vobb/gl.h>: the GL estimator
#     and figures; OpenGL, EGL, libpng), collision -> vobb::collision (the ODE/FCL experiment,
#     validate/collision/collision_experiment.h), assimp -> vobb::assimp (enable_assimp,
#     common/io/assimp_reader.h).
# The libraries are static, so their private dependencies are found again by vobbConfig.cmake.
# tests/install/ builds consumers against an installed tree.
include(CMakePackageConfigHelpers)

# Each component is an export set of its own, so that its packages are looked for only when it
# is asked for. Internal libraries are exported under detail_* names.
set(VOBB_CORE_LIBS vobb_common vobb_meshio vobb_exact vobb_fast vobb_fast_poly vobb_builder vobb_collision vobb_api)
set(VOBB_CORE_HELPERS vobb_cgal vobb_config)
set(VOBB_GL_LIBS vobb_fast_gl vobb_render vobb_png vobb_api_gl)
set(VOBB_COLLISION_LIBS vobb_collision_experiment)
set(VOBB_ASSIMP_LIBS)
if(VOBB_WITH_ASSIMP)
  set(VOBB_ASSIMP_LIBS vobb_meshio_assimp)
endif()
foreach(t IN LISTS VOBB_CORE_LIBS VOBB_CORE_HELPERS VOBB_GL_LIBS VOBB_COLLISION_LIBS VOBB_ASSIMP_LIBS)
  string(REGEX REPLACE "^vobb_" "detail_" name ${t})
  set_target_properties(${t} PROPERTIES EXPORT_NAME ${name})
endforeach()

# The public targets: vobb::vobb and one per component (each brings vobb::vobb, whose include
# folders the public headers need).
add_library(vobb_public_core INTERFACE)
target_link_libraries(vobb_public_core INTERFACE vobb_api)
target_include_directories(vobb_public_core INTERFACE $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>
                                                      $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/vobb/detail>)
set_target_properties(vobb_public_core PROPERTIES EXPORT_NAME vobb)
add_library(vobb_public_gl INTERFACE)
target_link_libraries(vobb_public_gl INTERFACE vobb_api_gl vobb_public_core)
set_target_properties(vobb_public_gl PROPERTIES EXPORT_NAME gl)
add_library(vobb_public_collision INTERFACE)
target_link_libraries(vobb_public_collision INTERFACE vobb_collision_experiment vobb_public_core)
set_target_properties(vobb_public_collision PROPERTIES EXPORT_NAME collision)
set(VOBB_ASSIMP_PUBLIC)
if(VOBB_WITH_ASSIMP)
  add_library(vobb_public_assimp INTERFACE)
  target_link_libraries(vobb_public_assimp INTERFACE vobb_meshio_assimp vobb_public_core)
  set_target_properties(vobb_public_assimp PROPERTIES EXPORT_NAME assimp)
  set(VOBB_ASSIMP_PUBLIC vobb_public_assimp)
endif()

set(VOBB_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/vobb)
foreach(set_name IN ITEMS Core Gl Collision Assimp)
  string(TOUPPER ${set_name} upper)
  if(set_name STREQUAL "Core")
    set(targets ${VOBB_CORE_LIBS} ${VOBB_CORE_HELPERS} vobb_public_core)
  elseif(set_name STREQUAL "Gl")
    set(targets ${VOBB_GL_LIBS} vobb_public_gl)
  elseif(set_name STREQUAL "Collision")
    set(targets ${VOBB_COLLISION_LIBS} vobb_public_collision)
  else()
    set(targets ${VOBB_ASSIMP_LIBS} ${VOBB_ASSIMP_PUBLIC})
  endif()
  if(targets)
    install(TARGETS ${targets} EXPORT vobb${set_name}Targets
            ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
    install(EXPORT vobb${set_name}Targets NAMESPACE vobb:: DESTINATION ${VOBB_CMAKE_DIR})
  endif()
endforeach()
install(TARGETS vobb vobb-make-analytic RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

# Headers: the face at include/vobb/, what it includes under include/vobb/detail/.
install(FILES ${PROJECT_SOURCE_DIR}/vobb/vobb.h ${PROJECT_SOURCE_DIR}/vobb/gl.h
              ${PROJECT_BINARY_DIR}/generated/vobb/config.h
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/vobb)
foreach(dir common exact fast builder collision render validate/collision)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${dir}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/vobb/detail/${dir}
          FILES_MATCHING PATTERN "*.h")
endforeach()

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/vobbConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/vobbConfig.cmake INSTALL_DESTINATION ${VOBB_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/vobbConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/vobbConfig.cmake ${PROJECT_BINARY_DIR}/vobbConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/VobbGmp.cmake
        DESTINATION ${VOBB_CMAKE_DIR})
