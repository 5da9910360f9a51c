# SPDX-License-Identifier: Apache-2.0
# Runs EXE and writes its stdout to OUT (only when it succeeds).
#   cmake -DEXE=program -DOUT=file -P write.cmake
execute_process(COMMAND "${EXE}" OUTPUT_FILE "${OUT}.tmp" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  file(REMOVE "${OUT}.tmp")
  message(FATAL_ERROR "${EXE} failed (${rc})")
endif()
file(RENAME "${OUT}.tmp" "${OUT}")
