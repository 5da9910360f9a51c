# SPDX-License-Identifier: Apache-2.0
# Sets TACSE3_TOOLS_COMMON_AVAILABLE: whether tools/common will define tacse3_tools_common.
# Tool folders sort before "common" (bench_accuracy, calibrate), so they test the conditions
# rather than the target, which does not exist yet when they are configured.
include("${PROJECT_SOURCE_DIR}/cmake/Tacse3TargetDeps.cmake")
tacse3_find_tomlpp()
if(TARGET tacse3_recording AND TARGET tacse3_dep_tomlpp)
  set(TACSE3_TOOLS_COMMON_AVAILABLE ON)
else()
  set(TACSE3_TOOLS_COMMON_AVAILABLE OFF)
endif()
