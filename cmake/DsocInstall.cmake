# Install rules for the dsoc package: headers, static (or shared) libraries, and a
# relocatable CMake package (dsocConfig.cmake + dsocConfigVersion.cmake) so that
#   find_package(dsoc 0.1 CONFIG REQUIRED [COMPONENTS visibility maps ...])
# gives the same namespaced targets as add_subdirectory(dsoc): dsoc::visibility,
# dsoc::maps, dsoc::sim, dsoc::interest, dsoc::trace, dsoc::protocol.
#
# One export set per component, so that a consumer without protobuf (say) can still
# use dsoc::visibility by asking only for the components it needs. What each
# component needs from the system is found by dsocConfig.cmake (find_dependency).
#
# Only library code is installed: programs, tests, benchmarks and fuzzers are not.
# Generated protobuf code: dsoc::protocol's public header messages.hpp includes the
# protoc output dsoc/protocol/dsoc.pb.h, so the package installs that one header
# beside it; consumers of dsoc::protocol must compile it against the same protobuf
# release dsoc was built with (the header checks PROTOBUF_VERSION and fails to
# compile otherwise). No other target sees it.

include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(DSOC_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/dsoc
  CACHE STRING "Where dsocConfig.cmake is installed, relative to the prefix")
mark_as_advanced(DSOC_INSTALL_CMAKEDIR)

# Components in dependency order (a component only needs those before it).
set(dsoc_install_components visibility maps sim interest trace protocol)
set(dsoc_installed_components "")

foreach(component ${dsoc_install_components})
  set(target dsoc_${component})
  if(NOT TARGET ${target})
    continue()
  endif()
  list(APPEND dsoc_installed_components ${component})
  install(TARGETS ${target}
    EXPORT dsoc-${component}-targets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dsoc_development
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dsoc_runtime
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT dsoc_runtime
    INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  # Public headers: <module>/include/dsoc/<module>/*.hpp (private headers live in src/).
  # protocol/'s connect_token.hpp and challenge_cookie.hpp belong to dsoc_connect_token,
  # a library of the programs that the package does not hold (protocol/CMakeLists.txt):
  # left out.
  get_target_property(source_dir ${target} SOURCE_DIR)
  install(DIRECTORY ${source_dir}/include/
    DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT dsoc_development
    FILES_MATCHING PATTERN "*.hpp" PATTERN "connect_token.hpp" EXCLUDE
    PATTERN "challenge_cookie.hpp" EXCLUDE)
  install(EXPORT dsoc-${component}-targets
    NAMESPACE dsoc::
    FILE dsoc-${component}-targets.cmake
    DESTINATION ${DSOC_INSTALL_CMAKEDIR} COMPONENT dsoc_development)
endforeach()

if(TARGET dsoc_protocol)
  # The protoc output messages.hpp includes (see the note at the top). protocol/
  # generates it into <binary dir>/generated/dsoc/protocol/.
  get_target_property(protocol_binary_dir dsoc_protocol BINARY_DIR)
  install(DIRECTORY ${protocol_binary_dir}/generated/
    DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT dsoc_development
    FILES_MATCHING PATTERN "*.pb.h")
endif()

configure_package_config_file(
  ${CMAKE_CURRENT_LIST_DIR}/dsocConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/dsocConfig.cmake
  INSTALL_DESTINATION ${DSOC_INSTALL_CMAKEDIR})
# 0.x: a minor release may change the API, so only the same MAJOR.MINOR matches.
write_basic_package_version_file(
  ${CMAKE_CURRENT_BINARY_DIR}/dsocConfigVersion.cmake
  VERSION ${PROJECT_VERSION}
  COMPATIBILITY SameMinorVersion)
install(FILES
  ${CMAKE_CURRENT_BINARY_DIR}/dsocConfig.cmake
  ${CMAKE_CURRENT_BINARY_DIR}/dsocConfigVersion.cmake
  DESTINATION ${DSOC_INSTALL_CMAKEDIR} COMPONENT dsoc_development)
