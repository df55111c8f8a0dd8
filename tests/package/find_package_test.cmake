# Installs the build into a scratch prefix, then configures, builds and runs the project in
# consumer/ against it, as another project would use zeroset.
#   cmake -DBUILD_DIR=... -DWORK_DIR=... -DCONSUMER_DIR=... -DCXX_COMPILER=... -DBUILD_TYPE=...
#         [-DLAUNCHER=ccache] -P find_package_test.cmake
foreach(var BUILD_DIR WORK_DIR CONSUMER_DIR CXX_COMPILER BUILD_TYPE)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "find_package_test: ${var} is not set")
  endif()
endforeach()

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()

set(prefix ${WORK_DIR}/prefix)
file(REMOVE_RECURSE ${WORK_DIR})
run("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix}
    --config ${BUILD_TYPE})

set(launcher "")
if(LAUNCHER)
  set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
# Only the scratch prefix may provide zeroset: no package registry, no other install.
run("configuring the consumer" ${CMAKE_COMMAND} -S ${CONSUMER_DIR} -B ${WORK_DIR}/build
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_CXX_COMPILER=${CXX_COMPILER}
    -DCMAKE_BUILD_TYPE=${BUILD_TYPE} -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF
    -DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF ${launcher})
if(NOT out MATCHES "zeroset [0-9.]+ from ([^\n]*)")
  message(FATAL_ERROR "the consumer did not say where zeroset came from:\n${out}")
endif()
string(FIND "${CMAKE_MATCH_1}" "${prefix}/" at)
if(NOT at EQUAL 0)
  message(FATAL_ERROR "zeroset was found in ${CMAKE_MATCH_1}, not in ${prefix}")
endif()
run("building the consumer" ${CMAKE_COMMAND} --build ${WORK_DIR}/build --config ${BUILD_TYPE})

find_program(consumer consumer PATHS ${WORK_DIR}/build ${WORK_DIR}/build/${BUILD_TYPE}
             NO_DEFAULT_PATH REQUIRED)
run("running the consumer" ${consumer})
message(STATUS "consumer printed:\n${out}")
# x^2 + y^2 + z^2 - r^2 at (1, 2, 3) with r = 2 is 10, its gradient (2, 4, 6);
# Cayley's 4 (x^2 + y^2 + z^2) + 16 x y z - 1 at (0.5, 0.5, 0.5) is 3 + 2 - 1 = 4.
foreach(line "equation F(1,2,3) = 10, grad F = 2 4 6" "cayley F(0.5,0.5,0.5) = 4")
  string(FIND "${out}" "${line}\n" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "expected the line '${line}'")
  endif()
endforeach()
if(NOT out MATCHES "cayley mesh: ([0-9]+) triangles" OR CMAKE_MATCH_1 LESS 100)
  message(FATAL_ERROR "expected a mesh of Cayley's cubic with at least 100 triangles")
endif()
