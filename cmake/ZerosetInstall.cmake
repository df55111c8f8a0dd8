# What `cmake --install` puts where (GNUInstallDirs layout), and the CMake package that lets
# another project write
#   find_package(zeroset 0.1 REQUIRED)
#   target_link_libraries(app PRIVATE zeroset::zeroset)
# The static libraries are exported under the namespace zeroset:: with the names the build uses
# (zeroset::expr, zeroset::surface, ...); zeroset::zeroset links them all. Helpers that only the
# build knows (warnings, -march=native, stb, the private zeroset/detail headers) are linked
# through $<BUILD_INTERFACE:...> in the modules, so nothing of them is exported.
include(CMakePackageConfigHelpers)

set(ZEROSET_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/zeroset
    CACHE STRING "Where zerosetConfig.cmake is installed, relative to the prefix")
mark_as_advanced(ZEROSET_INSTALL_CMAKEDIR)

# The umbrella target. Its build name cannot be `zeroset`: that is the command-line program.
add_library(zeroset_library INTERFACE)
add_library(zeroset::zeroset ALIAS zeroset_library)
set_target_properties(zeroset_library PROPERTIES EXPORT_NAME zeroset)
target_link_libraries(zeroset_library INTERFACE
  zeroset::core zeroset::expr zeroset::io zeroset::surface zeroset::render zeroset::floaters
  zeroset::mesh)

set(_zs_libraries zeroset_expr zeroset_io zeroset_surface zeroset_render zeroset_floaters
                  zeroset_mesh)
foreach(lib IN LISTS _zs_libraries)
  string(REPLACE "zeroset_" "" _zs_short ${lib})
  set_target_properties(${lib} PROPERTIES EXPORT_NAME ${_zs_short})
  # Objects built with the sanitizers need their runtime wherever they are linked.
  if(ZEROSET_SANITIZE)
    target_link_options(${lib} INTERFACE "$<INSTALL_INTERFACE:-fsanitize=address,undefined>")
  endif()
endforeach()
set_target_properties(zeroset_core PROPERTIES EXPORT_NAME core)

install(TARGETS zeroset_core zeroset_library ${_zs_libraries}
        EXPORT zerosetTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT development)
# The public headers: include/zeroset/** (none of them includes a zeroset/detail header).
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/zeroset
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT development
        FILES_MATCHING PATTERN "*.h")
install(EXPORT zerosetTargets
        NAMESPACE zeroset::
        DESTINATION ${ZEROSET_INSTALL_CMAKEDIR} COMPONENT development)

set(ZEROSET_CONFIG_OPENMP ${OpenMP_CXX_FOUND})
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/zerosetConfig.cmake.in
  ${PROJECT_BINARY_DIR}/zerosetConfig.cmake
  INSTALL_DESTINATION ${ZEROSET_INSTALL_CMAKEDIR})
# 0.x releases promise nothing across minor versions.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/zerosetConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/zerosetConfig.cmake
              ${PROJECT_BINARY_DIR}/zerosetConfigVersion.cmake
        DESTINATION ${ZEROSET_INSTALL_CMAKEDIR} COMPONENT development)

# The program (with the viewer compiled in when it is built), its bash completion, the
# license and the documentation.
install(TARGETS zeroset RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
set(_zs_completion ${PROJECT_BINARY_DIR}/completion/zeroset)
file(MAKE_DIRECTORY ${PROJECT_BINARY_DIR}/completion)
# A sanitizer build's program would report what its runtime holds at exit; that is no failure
# of the script it wrote.
add_custom_command(OUTPUT ${_zs_completion}
  COMMAND ${CMAKE_COMMAND} -E env ASAN_OPTIONS=detect_leaks=0
          $<TARGET_FILE:zeroset> completion bash --output ${_zs_completion}
  DEPENDS zeroset
  COMMENT "Generating the bash completion of zeroset"
  VERBATIM)
add_custom_target(zeroset_bash_completion ALL DEPENDS ${_zs_completion})
install(FILES ${_zs_completion}
        DESTINATION ${CMAKE_INSTALL_DATADIR}/bash-completion/completions COMPONENT runtime)
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE ${PROJECT_SOURCE_DIR}/README.md
        DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT runtime)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs
        DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT runtime)
