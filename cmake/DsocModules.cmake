# How a dsoc module declares its library and how a folder of programs, tests or
# benchmarks takes in its subfolders: one definition, used by every module.

# dsoc_add_component(<name> SOURCES <files...> [PUBLIC <deps...>] [PRIVATE <deps...>])
# The installable library dsoc_<name>, also known as dsoc::<name> (in the build and,
# by its export name, in the installed package: cmake/DsocInstall.cmake), with the
# public headers of <module>/include, C++20 for its users and our warning flags.
function(dsoc_add_component name)
  cmake_parse_arguments(C "" "" "SOURCES;PUBLIC;PRIVATE" ${ARGN})
  set(target dsoc_${name})
  add_library(${target} ${C_SOURCES})
  add_library(dsoc::${name} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME ${target})
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:include>)
  target_link_libraries(${target} PUBLIC ${C_PUBLIC} PRIVATE ${C_PRIVATE})
  target_compile_features(${target} PUBLIC cxx_std_20)
  dsoc_target_warnings(${target})
endfunction()

# dsoc_add_program_library(<target> [ALIAS <alias>] SOURCES <files...>
#                          [PUBLIC <deps...>] [PRIVATE <deps...>])
# A static library of the programs (never installed): the headers of the current
# folder's include/ for its users, our warning flags; <alias> (dsoc::x) if given.
function(dsoc_add_program_library target)
  cmake_parse_arguments(L "" "ALIAS" "SOURCES;PUBLIC;PRIVATE" ${ARGN})
  add_library(${target} STATIC ${L_SOURCES})
  if(L_ALIAS)
    add_library(${L_ALIAS} ALIAS ${target})
  endif()
  target_include_directories(${target} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(${target} PUBLIC ${L_PUBLIC} PRIVATE ${L_PRIVATE})
  dsoc_target_warnings(${target})
endfunction()

# dsoc_add_subdirectories(): every direct subfolder of the current one that has a
# CMakeLists.txt, in name order (one program, test suite or benchmark each).
function(dsoc_add_subdirectories)
  file(GLOB dirs LIST_DIRECTORIES true ${CMAKE_CURRENT_SOURCE_DIR}/*)
  foreach(dir ${dirs})
    if(IS_DIRECTORY ${dir} AND EXISTS ${dir}/CMakeLists.txt)
      add_subdirectory(${dir})
    endif()
  endforeach()
endfunction()
