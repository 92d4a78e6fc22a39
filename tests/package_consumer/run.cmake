# ctest driver: install the project into a scratch prefix, then configure, build and run the
# consumer project against it with find_package(mppi).
set(prefix ${WORK_DIR}/prefix)
file(REMOVE_RECURSE ${WORK_DIR})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BINARY_DIR} --prefix ${prefix}
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "install failed (${rc})")
endif()
# The installation is then copied elsewhere and the original removed: the package must work
# from wherever it is (its data folder follows it).
set(moved ${WORK_DIR}/moved_prefix)
file(COPY ${prefix}/ DESTINATION ${moved})
file(REMOVE_RECURSE ${prefix})
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/package_consumer -B ${WORK_DIR}/consumer
                -DCMAKE_PREFIX_PATH=${moved} -DCMAKE_BUILD_TYPE=Release RESULT_VARIABLE rc
                OUTPUT_VARIABLE configure_out)
string(FIND "${configure_out}" "mppi_DATA_DIR = ${moved}/share/mppi/data" found)
if(found EQUAL -1)
  message(FATAL_ERROR "mppi_DATA_DIR is not the moved installation's:\n${configure_out}")
endif()
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring the consumer failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR}/consumer RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building the consumer failed (${rc})")
endif()
execute_process(COMMAND ${WORK_DIR}/consumer/consumer RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the consumer ran but failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E env --unset=MPPI_DATA_DIR ${WORK_DIR}/consumer/sim_consumer ${moved}
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the simulator consumer ran but failed (${rc})")
endif()
