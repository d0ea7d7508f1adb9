# package.install_and_run_example (cmake -P): `cmake --install` of this build tree
# into a fresh prefix; then, against that prefix only,
#  1. examples/embed is configured, built and run, and its output checked;
#  2. all_headers/ compiles every installed header on its own and links one call
#     into every component;
# and nothing the consumers compile refers to dsoc's source or build tree or
# carries dsoc's warning flags.
include(${CMAKE_CURRENT_LIST_DIR}/package_test_common.cmake)

set(root ${WORK_DIR}/installed)
set(prefix ${root}/prefix)
file(REMOVE_RECURSE ${root})
run_step("installing ${DSOC_BUILD_DIR}"
  COMMAND ${CMAKE_COMMAND} --install ${DSOC_BUILD_DIR} --prefix ${prefix})

# The package holds libraries, public headers (dsoc::visibility's seeds in seeds/) and
# CMake files: no programs, no private headers (src/), no paths into the build or
# source tree.
file(GLOB_RECURSE installed RELATIVE ${prefix} ${prefix}/*)
set(config_dir "")
foreach(file ${installed})
  if(file MATCHES "^include/dsoc/[a-z]+/(seeds/)?[a-z0-9_]+\\.(hpp|pb\\.h)$"
     OR file MATCHES "^lib[^/]*/(.+/)?libdsoc_[a-z]+\\.(a|so.*)$")
    continue()
  elseif(file MATCHES "^(lib[^/]*/(.+/)?cmake/dsoc)/[A-Za-z-]+\\.cmake$")
    set(config_dir ${CMAKE_MATCH_1})
    file(READ ${prefix}/${file} text)
    foreach(tree ${DSOC_SOURCE_DIR} ${DSOC_BUILD_DIR})
      string(FIND "${text}" "${tree}/" at)
      if(NOT at EQUAL -1)
        message(FATAL_ERROR "package test: ${file} refers to ${tree}: not relocatable")
      endif()
    endforeach()
  else()
    message(FATAL_ERROR "package test: unexpected file in the package: ${file}")
  endif()
endforeach()
if(NOT EXISTS ${prefix}/${config_dir}/dsocConfig.cmake
   OR NOT EXISTS ${prefix}/${config_dir}/dsocConfigVersion.cmake
   OR NOT EXISTS ${prefix}/include/dsoc/visibility/interest_manager.hpp)
  message(FATAL_ERROR "package test: dsocConfig.cmake, its version file or the headers "
    "are missing from ${prefix}:\n${installed}")
endif()

consumer_configure_args(args)
list(APPEND args -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)

# build_consumer(<name> <source dir>): configures and builds a consumer project in
# ${root}/<name>; fails on any compiler warning or any trace of dsoc's trees.
function(build_consumer name source_dir)
  set(dir ${root}/${name})
  run_step("configuring ${name} against the installed package"
    COMMAND ${CMAKE_COMMAND} -S ${source_dir} -B ${dir} ${args})
  file(STRINGS ${dir}/CMakeCache.txt dsoc_dir REGEX "^dsoc_DIR:")
  if(NOT dsoc_dir MATCHES "=${prefix}/")
    message(FATAL_ERROR "package test: ${name} found dsoc elsewhere: ${dsoc_dir}")
  endif()
  run_step("building ${name}" COMMAND ${CMAKE_COMMAND} --build ${dir} OUTPUT_VARIABLE log)
  if(log MATCHES "warning:")
    message(FATAL_ERROR "package test: ${name} builds with warnings:\n${log}")
  endif()
  file(READ ${dir}/compile_commands.json commands)
  string(REPLACE "${root}" "<work>" commands "${commands}")
  foreach(leak "-I${DSOC_SOURCE_DIR}" "-isystem ${DSOC_SOURCE_DIR}" "${DSOC_BUILD_DIR}"
          "-Werror" "-Wold-style-cast" "-Wshadow" "DSOC_VERSION_STRING")
    string(FIND "${commands}" "${leak}" at)
    if(NOT at EQUAL -1)
      message(FATAL_ERROR "package test: dsoc leaks '${leak}' into ${name}'s compile "
        "commands:\n${commands}")
    endif()
  endforeach()
endfunction()

build_consumer(example ${DSOC_SOURCE_DIR}/examples/embed)
run_step("running the example" COMMAND ${root}/example/dsoc-embed-example OUTPUT_VARIABLE output)
check_example_output("${output}")

build_consumer(all_headers ${CMAKE_CURRENT_LIST_DIR}/all_headers)
run_step("running all_headers' link check" COMMAND ${root}/all_headers/link_every_component)
message(STATUS "package test: installed, built and ran examples/embed and all_headers")
