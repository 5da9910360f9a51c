# SPDX-License-Identifier: Apache-2.0
# The committed protocol/tacse3.dbc must be exactly what tacse3-dbcgen writes from the table.
#   cmake -DDBCGEN=exe|args -DCOMMITTED=protocol/tacse3.dbc -DOUT=file -P check_dbc.cmake
string(REPLACE "|" ";" DBCGEN "${DBCGEN}")
execute_process(COMMAND ${DBCGEN} --output "${OUT}" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "tacse3-dbcgen failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files "${OUT}" "${COMMITTED}"
                RESULT_VARIABLE diff)
if(NOT diff EQUAL 0)
  message(FATAL_ERROR "protocol/tacse3.dbc is out of date with the message table: run "
                      "`cmake --build <build dir> --target tacse3_dbc_update` and commit it")
endif()
message(STATUS "protocol/tacse3.dbc matches the message table")
