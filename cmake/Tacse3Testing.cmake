# SPDX-License-Identifier: Apache-2.0
# GoogleTest is compiled from source with the project's own compiler and flags, so the same
# recipe serves the host, the sanitizer build and the cross builds run under qemu-user.
macro(tacse3_enable_gtest)
  if(NOT TARGET gtest_main)
    set(INSTALL_GTEST OFF CACHE BOOL "" FORCE)
    set(BUILD_GMOCK OFF CACHE BOOL "" FORCE)
    add_subdirectory("${TACSE3_GTEST_SOURCE_DIR}" "${CMAKE_BINARY_DIR}/_googletest" EXCLUDE_FROM_ALL SYSTEM)
  endif()
  include(GoogleTest)
endmacro()

# tacse3_add_gtest(<name> SOURCES <files...> LIBS <targets...> [LABELS <labels...>] [TIMEOUT s]
#                  [COST s])
# One executable per test file; tests are discovered at ctest time (PRE_TEST) so discovery
# also works through CMAKE_CROSSCOMPILING_EMULATOR.
function(tacse3_add_gtest name)
  cmake_parse_arguments(ARG "" "TIMEOUT;COST" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest_main)
  tacse3_warnings(${name})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 600)
  endif()
  # COST (seconds, roughly) starts a slow program's tests first when ctest has no timing history
  # of its own, as on CI's fresh clone; otherwise they may start last and run alone at the end.
  if(NOT ARG_COST)
    set(ARG_COST 0)
  endif()
  gtest_discover_tests(${name} DISCOVERY_MODE PRE_TEST DISCOVERY_TIMEOUT 120
                       PROPERTIES TIMEOUT ${ARG_TIMEOUT} LABELS "${ARG_LABELS}" COST ${ARG_COST})
endfunction()
