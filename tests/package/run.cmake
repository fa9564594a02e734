# ctest's package test: installs the build tree into BINARY/package-test/prefix, configures and builds the
# consumer project in this folder against it, and runs it. cmake -DBINARY=<build> -DSOURCE=<this folder> -P run.cmake
set(root "${BINARY}/package-test")
file(REMOVE_RECURSE "${root}")
function(step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("${out}")
  if(NOT code EQUAL 0)
    message(FATAL_ERROR "failed (${code}): ${ARGN}\n${err}")
  endif()
endfunction()
step(${CMAKE_COMMAND} --install "${BINARY}" --prefix "${root}/prefix")
step(${CMAKE_COMMAND} -S "${SOURCE}" -B "${root}/build" -DCMAKE_BUILD_TYPE=Release
     "-DCMAKE_PREFIX_PATH=${root}/prefix")
step(${CMAKE_COMMAND} --build "${root}/build")
step("${root}/build/consumer" "${root}/out")
