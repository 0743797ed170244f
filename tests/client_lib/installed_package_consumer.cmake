# ctest script (cmake -P): installs the telegrasp_client component of BUILD_DIR into a scratch
# prefix, checks the exported targets, then configures, builds and runs tests/consumer against
# that prefix only. Inputs: BUILD_DIR, WORK_DIR, CONSUMER_SOURCE_DIR, CXX_COMPILER, and the DDS
# domain for the consumer in the environment (TELEGRASP_TEST_DOMAIN: run under
# telegrasp-test-domains, which holds it for this script and the consumer).
cmake_minimum_required(VERSION 3.22)
foreach(var BUILD_DIR WORK_DIR CONSUMER_SOURCE_DIR CXX_COMPILER)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "installed_package_consumer.cmake: -D${var}=... is required")
  endif()
endforeach()
if(NOT "$ENV{TELEGRASP_TEST_DOMAIN}" MATCHES "^[0-9]+$")
  message(FATAL_ERROR "installed_package_consumer.cmake: TELEGRASP_TEST_DOMAIN is not set; run it under telegrasp-test-domains")
endif()

# A folder of this run's own, so that two ctest runs on one build tree do not share it; removed
# when the test passes.
string(RANDOM LENGTH 8 ALPHABET abcdefghijklmnopqrstuvwxyz0123456789 run)
set(WORK_DIR ${WORK_DIR}/run-${run})
set(prefix ${WORK_DIR}/prefix)
file(REMOVE_RECURSE ${WORK_DIR})

message(STATUS "1. install the telegrasp_client component into ${prefix}")
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix} --component telegrasp_client
  COMMAND_ERROR_IS_FATAL ANY)

message(STATUS "2. check the installed package")
file(GLOB_RECURSE targets_file ${prefix}/*/telegraspTargets.cmake)
if(NOT targets_file)
  message(FATAL_ERROR "no telegraspTargets.cmake under ${prefix}")
endif()
file(GLOB_RECURSE targets_files ${prefix}/*/telegraspTargets*.cmake)
foreach(f IN LISTS targets_files)
  file(READ ${f} text)
  # The static libraries are inside the .so: they must not appear anywhere.
  foreach(forbidden telegrasp_idl telegrasp_client_conversions)
    if(text MATCHES "${forbidden}")
      message(FATAL_ERROR "${f} mentions ${forbidden}")
    endif()
  endforeach()
  # Fast DDS is a private dependency: consumers link Eigen only. (CMake may still list the .so's
  # own shared dependencies in IMPORTED_LINK_DEPENDENT_LIBRARIES, which only guides -rpath-link.)
  string(REGEX MATCHALL "INTERFACE_LINK_LIBRARIES[^\n]*" interface_links "${text}")
  if(interface_links MATCHES "fast")
    message(FATAL_ERROR "${f}: consumers would link Fast DDS: ${interface_links}")
  endif()
endforeach()
foreach(f include/telegrasp/client/client.h include/telegrasp/client/types.h share/telegrasp/telegrasp_profiles.xml)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "${prefix}/${f} was not installed")
  endif()
endforeach()

message(STATUS "3. configure and build tests/consumer with CMAKE_PREFIX_PATH=${prefix}")
execute_process(COMMAND ${CMAKE_COMMAND} -S ${CONSUMER_SOURCE_DIR} -B ${WORK_DIR}/build
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_CXX_COMPILER=${CXX_COMPILER} -DCMAKE_BUILD_TYPE=Release
  COMMAND_ERROR_IS_FATAL ANY)
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR}/build COMMAND_ERROR_IS_FATAL ANY)

message(STATUS "4. run it")
execute_process(COMMAND ${WORK_DIR}/build/telegrasp-consumer $ENV{TELEGRASP_TEST_DOMAIN}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "consumer output:\n${out}${err}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "telegrasp-consumer exited with ${rc}")
endif()
if(NOT out MATCHES "published sample 1")
  message(FATAL_ERROR "telegrasp-consumer did not publish")
endif()
file(REMOVE_RECURSE ${WORK_DIR})
