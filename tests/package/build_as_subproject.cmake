# package.fetchcontent_subproject (cmake -P): configures subproject/ (an outer
# project that takes dsoc with FetchContent; it checks at configure time that dsoc
# defines only libraries and leaves the outer settings alone), builds the example
# program in it (and so only the libraries it links), and checks its output.
include(${CMAKE_CURRENT_LIST_DIR}/package_test_common.cmake)

set(dir ${WORK_DIR}/subproject)
file(REMOVE_RECURSE ${dir})
# Debug: the outer project's own choice (dsoc must keep it), and dsoc's libraries
# compile about a quarter quicker unoptimized (46 s of CPU cold, measured).
set(BUILD_TYPE Debug)
consumer_configure_args(args)
run_step("configuring an outer project that takes dsoc with FetchContent"
  COMMAND ${CMAKE_COMMAND} -S ${CMAKE_CURRENT_LIST_DIR}/subproject -B ${dir} ${args}
    -DDSOC_SOURCE_DIR=${DSOC_SOURCE_DIR} -DOUTER_BUILD_TYPE=${BUILD_TYPE})
run_step("building the example inside the outer project"
  COMMAND ${CMAKE_COMMAND} --build ${dir} --target dsoc-embed-example)
run_step("running the example" COMMAND ${dir}/dsoc-embed-example OUTPUT_VARIABLE output)
check_example_output("${output}")
message(STATUS "package test: dsoc as a FetchContent subproject: libraries only, example runs")
