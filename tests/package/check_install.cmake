# cmake -DBUILD_DIR=... -DWORK_DIR=... -DCONSUMER_DIR=... -DFortran_COMPILER=... -DVERSION=...
#       -DGENERATOR=... -P check_install.cmake
# Installs the build into WORK_DIR/prefix, checks the layout (programs, modules, package files),
# then configures, builds and runs tests/package/consumer, a separate CMake project that finds
# the installed knotflow with find_package(knotflow) and links knotflow::knotflow_lib.
foreach(var BUILD_DIR WORK_DIR CONSUMER_DIR Fortran_COMPILER VERSION GENERATOR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "check_install.cmake: ${var} not given")
  endif()
endforeach()

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(run_output "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
run("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})

# What the installation must hold; the tests' modules must not be there.
file(GLOB cmake_dirs ${prefix}/lib*/cmake/knotflow)
list(LENGTH cmake_dirs n)
if(NOT n EQUAL 1)
  message(FATAL_ERROR "expected one <prefix>/lib*/cmake/knotflow, found: ${cmake_dirs}")
endif()
foreach(f bin/knotflow-accuracy include/knotflow/kf_kinds.mod include/knotflow/kf_build_info.mod)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
foreach(f knotflowConfig.cmake knotflowConfigVersion.cmake knotflowTargets.cmake)
  if(NOT EXISTS ${cmake_dirs}/${f})
    message(FATAL_ERROR "not installed: ${cmake_dirs}/${f}")
  endif()
endforeach()
file(GLOB stray ${prefix}/include/knotflow/test_*.mod)
if(stray)
  message(FATAL_ERROR "test modules installed: ${stray}")
endif()

set(build ${WORK_DIR}/consumer-build)
run("configuring the consumer" ${CMAKE_COMMAND} -S ${CONSUMER_DIR} -B ${build} -G ${GENERATOR}
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_Fortran_COMPILER=${Fortran_COMPILER})
run("building the consumer" ${CMAKE_COMMAND} --build ${build})
run("running the consumer" ${build}/consumer ${VERSION})
message(STATUS "${run_output}")
if(NOT run_output MATCHES "consumer: ok")
  message(FATAL_ERROR "the consumer did not report ok: ${run_output}")
endif()
