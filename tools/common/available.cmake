# SPDX-License-Identifier: Apache-2.0
# Sets TACSE3_TOOLS_COMMON_AVAILABLE: whether tools/common will define tacse3_tools_common.
# Tool folders sort before "common" (bench_accuracy, calibrate), so they test the conditions
# rather than the target, which does not exist yet when they are configured.
find_path(TACSE3_TOMLPP_INCLUDE_DIR toml++/toml.h)
if(NOT TACSE3_TOMLPP_INCLUDE_DIR AND CMAKE_CROSSCOMPILING)
  find_path(TACSE3_TOMLPP_HOST_INCLUDE_DIR toml++/toml.h PATHS /usr/include
            NO_CMAKE_FIND_ROOT_PATH NO_DEFAULT_PATH)
endif()
if(TARGET tacse3_recording AND (TACSE3_TOMLPP_INCLUDE_DIR OR TACSE3_TOMLPP_HOST_INCLUDE_DIR))
  set(TACSE3_TOOLS_COMMON_AVAILABLE ON)
else()
  set(TACSE3_TOOLS_COMMON_AVAILABLE OFF)
endif()
