# SPDX-License-Identifier: Apache-2.0
# tacse3: manual pages and bash completion of the packaged programs, both made from each built
# program's own --help and --version, so they cannot drift from the code:
#   build/<preset>/man/<program>.1.gz                   Debian's help2man (optional for a build;
#                                                       the package needs it)
#   build/<preset>/bash-completion/<program>            cmake/tacse3_completion.cmake
# Cross builds run the programs under CMAKE_CROSSCOMPILING_EMULATOR (qemu-user).
# tacse3_man_completion(<programs...>) adds the target tacse3_man_completion (built by ALL) and
# sets TACSE3_MAN_PAGES / TACSE3_COMPLETIONS to the generated files.
include_guard(GLOBAL)

find_program(TACSE3_HELP2MAN help2man)

# One line per program for the NAME section of its manual page.
set(_tacse3_man_name_tacse3d "tactile SE(3) motion estimation daemon for a dual DM-Tac gripper")
set(_tacse3_man_name_tacse3-canmon "decode and monitor tacse3 CAN traffic")
set(_tacse3_man_name_tacse3-ctl "send a command to a tacse3 gripper and wait for its ACK")
set(_tacse3_man_name_tacse3-replay "run the tacse3 firmware pipeline over a recording")
set(_tacse3_man_name_tacse3-calibrate "fit a tacse3 calibration file to recordings")
set(_tacse3_man_name_tacse3-sim "render a simulated tacse3 grasp as a recording")
set(_tacse3_man_name_tacse3-demo "simulate a grasp and run the tacse3 pipeline on it")
set(_tacse3_man_name_tacse3-truth "rebuild a recording's truth.csv from robot pose logs")

function(tacse3_man_completion)
  set(runner "")
  if(CMAKE_CROSSCOMPILING_EMULATOR)
    list(JOIN CMAKE_CROSSCOMPILING_EMULATOR " " runner)
    string(APPEND runner " ")
  endif()
  set(man_dir "${CMAKE_BINARY_DIR}/man")
  set(comp_dir "${CMAKE_BINARY_DIR}/bash-completion")
  set(pages "")
  set(completions "")
  foreach(program IN LISTS ARGN)
    set(comp "${comp_dir}/${program}")
    add_custom_command(
      OUTPUT "${comp}"
      COMMAND "${CMAKE_COMMAND}" "-DPROGRAM=$<TARGET_FILE:${program}>" "-DNAME=${program}"
              "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}" "-DOUT=${comp}"
              -P "${PROJECT_SOURCE_DIR}/cmake/tacse3_completion.cmake"
      DEPENDS ${program} "${PROJECT_SOURCE_DIR}/cmake/tacse3_completion.cmake"
      COMMENT "bash completion of ${program} from its --help"
      VERBATIM)
    list(APPEND completions "${comp}")
    if(TACSE3_HELP2MAN)
      set(page "${man_dir}/${program}.1")
      set(name "${_tacse3_man_name_${program}}")
      if(NOT name)
        set(name "${program}")
      endif()
      # help2man runs "<program> --help" through the shell, so the emulator can lead the command.
      add_custom_command(
        OUTPUT "${page}.gz"
        COMMAND "${CMAKE_COMMAND}" -E make_directory "${man_dir}"
        COMMAND "${TACSE3_HELP2MAN}" --no-info --section=1 "--source=tacse3 ${PROJECT_VERSION}"
                "--name=${name}" "--output=${page}" "${runner}$<TARGET_FILE:${program}>"
        COMMAND gzip -9nf "${page}"
        DEPENDS ${program}
        COMMENT "manual page of ${program} (help2man)"
        VERBATIM)
      list(APPEND pages "${page}.gz")
    endif()
  endforeach()
  if(NOT TACSE3_HELP2MAN)
    message(STATUS "help2man not found: no manual pages (the .deb needs them: apt-get install help2man)")
  endif()
  add_custom_target(tacse3_man_completion ALL DEPENDS ${pages} ${completions})
  # Host only: bash runs the completions against the programs' own --help.
  if(TACSE3_BUILD_TESTS AND NOT CMAKE_CROSSCOMPILING)
    set(programs "")
    foreach(program IN LISTS ARGN)
      list(APPEND programs "$<TARGET_FILE:${program}>")
    endforeach()
    add_test(NAME tools_bash_completion
             COMMAND bash "${PROJECT_SOURCE_DIR}/tests/tools/completion_test.sh" "${comp_dir}"
                     ${programs})
    set_tests_properties(tools_bash_completion PROPERTIES LABELS tools TIMEOUT 120)
  endif()
  set(TACSE3_MAN_PAGES "${pages}" PARENT_SCOPE)
  set(TACSE3_COMPLETIONS "${completions}" PARENT_SCOPE)
endfunction()
