# cmake -DMODE=find_package|add_subdirectory -DCTXFUSE_SOURCE_DIR=... -DCONSUMER_SOURCE_DIR=...
#       -DWORK_DIR=... -DGENERATOR=... [-DMAKE_PROGRAM=...] -DCXX_COMPILER=... -DBUILD_TYPE=...
#       -P build_consumer.cmake
# Configures, builds and runs tests/package/consumer against ctxfuse; any failing step ends
# the script with its output and a non-zero status, which is what ctest checks.
cmake_minimum_required(VERSION 3.22)

foreach(var IN ITEMS MODE CTXFUSE_SOURCE_DIR CONSUMER_SOURCE_DIR WORK_DIR GENERATOR CXX_COMPILER BUILD_TYPE)
  if(NOT DEFINED ${var} OR "${${var}}" STREQUAL "")
    message(FATAL_ERROR "build_consumer.cmake: -D${var}=... is required")
  endif()
endforeach()

function(run_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    string(JOIN " " command_line ${ARGN})
    message(FATAL_ERROR "${what} failed (exit ${rc}):\n${command_line}\n${out}")
  endif()
  message(STATUS "${what}: ok")
endfunction()

# Reads one entry of a CMakeCache.txt into out_var (empty when absent).
function(read_cache_entry cache_file entry out_var)
  file(STRINGS ${cache_file} line REGEX "^${entry}:[A-Z]+=")
  string(REGEX REPLACE "^${entry}:[A-Z]+=" "" value "${line}")
  set(${out_var} "${value}" PARENT_SCOPE)
endfunction()

# A fresh tree every run: a stale cache could hide a broken install rule.
file(REMOVE_RECURSE ${WORK_DIR})
set(generator_args -G ${GENERATOR} -DCMAKE_CXX_COMPILER=${CXX_COMPILER} -DCMAKE_BUILD_TYPE=${BUILD_TYPE})
if(MAKE_PROGRAM)
  list(APPEND generator_args -DCMAKE_MAKE_PROGRAM=${MAKE_PROGRAM})
endif()
set(consumer_build ${WORK_DIR}/consumer-build)

if(MODE STREQUAL "find_package")
  set(prefix ${WORK_DIR}/prefix)
  run_step("configure ctxfuse" ${CMAKE_COMMAND} -S ${CTXFUSE_SOURCE_DIR} -B ${WORK_DIR}/ctxfuse-build
    ${generator_args} -DCTXFUSE_BUILD_TESTS=OFF -DCTXFUSE_BUILD_BENCH=OFF
    -DCTXFUSE_BUILD_TOOLS=OFF -DCTXFUSE_BUILD_EXAMPLES=OFF)
  run_step("install ctxfuse" ${CMAKE_COMMAND} --install ${WORK_DIR}/ctxfuse-build --prefix ${prefix})
  run_step("configure consumer (find_package)" ${CMAKE_COMMAND} -S ${CONSUMER_SOURCE_DIR} -B ${consumer_build}
    ${generator_args} -DCONSUMER_MODE=find_package -DCMAKE_PREFIX_PATH=${prefix}
    -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON)
  # The package must come from the fresh prefix, not from some other ctxfuse on the machine.
  read_cache_entry(${consumer_build}/CMakeCache.txt ctxfuse_DIR found_dir)
  file(REAL_PATH "${prefix}" prefix_real)
  file(REAL_PATH "${found_dir}" found_real)
  string(FIND "${found_real}" "${prefix_real}/" at)
  if(NOT at EQUAL 0)
    message(FATAL_ERROR "consumer found ctxfuse in '${found_dir}', expected under '${prefix}'")
  endif()
elseif(MODE STREQUAL "add_subdirectory")
  run_step("configure consumer (add_subdirectory)" ${CMAKE_COMMAND} -S ${CONSUMER_SOURCE_DIR} -B ${consumer_build}
    ${generator_args} -DCONSUMER_MODE=add_subdirectory -DCTXFUSE_SOURCE_DIR=${CTXFUSE_SOURCE_DIR})
  # As a sub-project ctxfuse must define its library only, not its tests, tools or benchmarks.
  foreach(option IN ITEMS CTXFUSE_BUILD_TESTS CTXFUSE_BUILD_BENCH CTXFUSE_BUILD_TOOLS CTXFUSE_BUILD_EXAMPLES)
    read_cache_entry(${consumer_build}/CMakeCache.txt ${option} value)
    if(value)
      message(FATAL_ERROR "${option} is '${value}' in a consumer that add_subdirectory()s ctxfuse; expected OFF")
    endif()
  endforeach()
else()
  message(FATAL_ERROR "build_consumer.cmake: MODE must be find_package or add_subdirectory, not '${MODE}'")
endif()

run_step("build consumer" ${CMAKE_COMMAND} --build ${consumer_build})
run_step("run consumer" ${consumer_build}/ctxfuse_consumer)
