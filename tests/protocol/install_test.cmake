# SPDX-License-Identifier: Apache-2.0
# Installs the protocol component into a temporary prefix, then builds the controller example
# against it with find_package(tacse3 COMPONENTS protocol), and a one-file program with pkg-config.
#   cmake -DBUILD_DIR= -DSOURCE_DIR= -DWORK_DIR= -DGENERATOR= -DCXX= [-DTOOLCHAIN=] [-DFLAGS=]
#         -P install_test.cmake
set(prefix "${WORK_DIR}/prefix")
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
endfunction()
# The CMake package names the shared library too, so the runtime component goes with it.
run(${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${prefix}" --component protocol)
run(${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${prefix}" --component protocol_runtime)
foreach(f include/tacse3/protocol/protocol.hpp share/tacse3-protocol/tacse3.dbc)
  if(NOT EXISTS "${prefix}/${f}")
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
set(args -S "${SOURCE_DIR}/examples/controller" -B "${WORK_DIR}/example" -G "${GENERATOR}"
    "-DCMAKE_PREFIX_PATH=${prefix}" "-DCMAKE_CXX_COMPILER=${CXX}" -DCMAKE_BUILD_TYPE=Release)
if(TOOLCHAIN)
  # The toolchain confines package search to the target sysroot; point at the package directly.
  list(APPEND args "-DCMAKE_TOOLCHAIN_FILE=${TOOLCHAIN}" "-Dtacse3_DIR=${prefix}/lib/cmake/tacse3")
endif()
if(FLAGS)
  list(APPEND args "-DCMAKE_CXX_FLAGS=${FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${FLAGS}")
endif()
run(${CMAKE_COMMAND} ${args})
run(${CMAKE_COMMAND} --build "${WORK_DIR}/example")
message(STATUS "controller example built against the installed package")

# pkg-config: compile and link a program with only the flags the .pc file gives (-std included).
file(GLOB pc_file "${prefix}/lib*/pkgconfig/tacse3-protocol.pc" "${prefix}/lib/*/pkgconfig/tacse3-protocol.pc")
if(NOT pc_file)
  message(FATAL_ERROR "tacse3-protocol.pc not installed")
endif()
get_filename_component(pc_dir "${pc_file}" DIRECTORY)
set(ENV{PKG_CONFIG_PATH} "${pc_dir}")
execute_process(COMMAND pkg-config --cflags --libs tacse3-protocol RESULT_VARIABLE rc
                OUTPUT_VARIABLE pc_flags OUTPUT_STRIP_TRAILING_WHITESPACE)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "pkg-config cannot read tacse3-protocol.pc")
endif()
separate_arguments(pc_flags UNIX_COMMAND "${pc_flags}")
file(WRITE "${WORK_DIR}/pc.cpp" "#include <tacse3/protocol/protocol.hpp>\nint main() {\n  tacse3::protocol::CycleFrames f;\n  return tacse3::protocol::encode_cycle(tacse3::protocol::Cycle{}, 0, {}, f) == tacse3::protocol::Status::kOk && f.count == 5 ? 0 : 1;\n}\n")
separate_arguments(extra UNIX_COMMAND "${FLAGS}")
run(${CXX} ${extra} "${WORK_DIR}/pc.cpp" -o "${WORK_DIR}/pc" ${pc_flags})
message(STATUS "pkg-config: ${pc_flags}")
