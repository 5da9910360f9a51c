# SPDX-License-Identifier: Apache-2.0
# Runs one command and checks its exit status and output (tool tests of tests/protocol).
#   cmake -DCMD=a|b|c -DEXPECT_RC=0 [-DEXPECT_OUT=regex] [-DEXPECT_ERR=regex] [-DINPUT=file]
#         -P expect.cmake
string(REPLACE "|" ";" CMD "${CMD}")
if(DEFINED INPUT)
  execute_process(COMMAND ${CMD} INPUT_FILE "${INPUT}" RESULT_VARIABLE rc OUTPUT_VARIABLE out
                  ERROR_VARIABLE err TIMEOUT 60)
else()
  execute_process(COMMAND ${CMD} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err
                  TIMEOUT 60)
endif()
message(STATUS "command: ${CMD}\nexit: ${rc}\nstdout:\n${out}\nstderr:\n${err}")
if(NOT rc STREQUAL "${EXPECT_RC}")
  message(FATAL_ERROR "exit status ${rc}, expected ${EXPECT_RC}")
endif()
if(DEFINED EXPECT_OUT AND NOT out MATCHES "${EXPECT_OUT}")
  message(FATAL_ERROR "stdout does not match: ${EXPECT_OUT}")
endif()
if(DEFINED EXPECT_ERR AND NOT err MATCHES "${EXPECT_ERR}")
  message(FATAL_ERROR "stderr does not match: ${EXPECT_ERR}")
endif()
