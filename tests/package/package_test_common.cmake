# Helpers shared by the package test scripts (run with cmake -P). Inputs, passed by
# tests/package/CMakeLists.txt: DSOC_SOURCE_DIR, DSOC_BUILD_DIR, DSOC_VERSION,
# WORK_DIR, GENERATOR, CXX, LAUNCHER, BUILD_TYPE, SANITIZE.

# run_step(<what> COMMAND ...): runs the command; on failure stops the test with
# <what>, the exit status and the command's output.
function(run_step what)
  cmake_parse_arguments(S "" "OUTPUT_VARIABLE" "COMMAND" ${ARGN})
  execute_process(COMMAND ${S_COMMAND} RESULT_VARIABLE status
    OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT status EQUAL 0)
    string(REPLACE ";" " " shown "${S_COMMAND}")
    message(FATAL_ERROR "package test: ${what} failed (exit ${status})\n  ${shown}\n${out}")
  endif()
  if(S_OUTPUT_VARIABLE)
    set(${S_OUTPUT_VARIABLE} "${out}" PARENT_SCOPE)
  endif()
endfunction()

# The -D arguments a consumer project is configured with: this build's compiler,
# launcher (ccache), build type and sanitizers, and strict warnings for the
# consumer's own code (dsoc's headers come in as system headers of imported targets).
function(consumer_configure_args out_var)
  set(args -G ${GENERATOR} -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_EXPORT_COMPILE_COMMANDS=ON)
  if(LAUNCHER)
    list(APPEND args -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
  endif()
  if(BUILD_TYPE)
    list(APPEND args -DCMAKE_BUILD_TYPE=${BUILD_TYPE})
  endif()
  set(flags "-Wall -Wextra -Wpedantic")
  if(SANITIZE)
    string(APPEND flags " -fsanitize=${SANITIZE} -fno-omit-frame-pointer")
    list(APPEND args "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=${SANITIZE}")
  endif()
  list(APPEND args "-DCMAKE_CXX_FLAGS=${flags}")
  set(${out_var} ${args} PARENT_SCOPE)
endfunction()

# check_example_output(<output>): what examples/embed/main.cpp must print on its
# default map (two_halls.map: two halls joined by one doorway) over 300 ticks.
function(check_example_output output)
  set(problems "")
  if(NOT output MATCHES "^dsoc ${DSOC_VERSION}\n")
    list(APPEND problems "first line is not 'dsoc ${DSOC_VERSION}' (dsoc::version())")
  endif()
  # The walkers of clients 1 and 2 walk through the doorway and back: in the same
  # hall or in line with the doorway the others are replicated, behind the dividing
  # wall they are not, so both clients must see entities both enter and leave.
  foreach(client 1 2)
    if(NOT output MATCHES "summary client ${client}: ([0-9]+) enter, ([0-9]+) leave, ([0-9]+) of 7 replicated at the end, ([0-9]+) teleports")
      list(APPEND problems "no summary line for client ${client}")
      continue()
    endif()
    set(enters ${CMAKE_MATCH_1})
    set(leaves ${CMAKE_MATCH_2})
    set(replicated ${CMAKE_MATCH_3})
    set(teleports ${CMAKE_MATCH_4})
    if(leaves LESS 2)
      list(APPEND problems "client ${client}: ${leaves} leave events: its walker crosses the doorway, so others must be hidden by the wall at times")
    endif()
    # The events are a diff: the final set is everything that entered and did not leave.
    math(EXPR expected "${enters} - ${leaves}")
    if(NOT replicated EQUAL expected)
      list(APPEND problems "client ${client}: ${replicated} replicated at the end, but ${enters} enter - ${leaves} leave = ${expected}")
    endif()
    # Walkers move at most 300 u/s and declare 320 u/s: a teleport is a bug.
    if(NOT teleports EQUAL 0)
      list(APPEND problems "client ${client}: ${teleports} teleports although every walker keeps its motion limits")
    endif()
  endforeach()
  # Removing an entity makes it leave every client that had it, on the same tick.
  if(NOT output MATCHES "tick 180 entity 107 removed\n")
    list(APPEND problems "entity 107 was not removed at tick 180")
  endif()
  string(REGEX MATCHALL "tick 180 client [0-9]+:[^\n]* leave[^\n]* 107" removal_leaves "${output}")
  string(REGEX MATCHALL "tick (18[1-9]|19[0-9]|2[0-9][0-9]|300) client [0-9]+:[^\n]* 107[ \n]" later "${output}")
  if(removal_leaves STREQUAL "" OR NOT later STREQUAL "")
    list(APPEND problems "entity 107 did not leave at tick 180, or appeared after its removal")
  endif()
  # A client that connects mid-game gets its first set at once; after it disconnects
  # it has no decisions.
  if(NOT output MATCHES "client 3 connects[^\n]*\ntick 90 client 3: enter ")
    list(APPEND problems "client 3 did not get an enter set on the tick it connected (90)")
  endif()
  if(output MATCHES "tick (24[0-9]|2[5-9][0-9]|300) client 3:" OR output MATCHES "summary client 3")
    list(APPEND problems "client 3 still has decisions after it disconnected at tick 240")
  endif()
  if(problems)
    string(REPLACE ";" "\n  " problems "${problems}")
    message(FATAL_ERROR "package test: the example's output is wrong:\n  ${problems}\n--- output ---\n${output}")
  endif()
endfunction()
