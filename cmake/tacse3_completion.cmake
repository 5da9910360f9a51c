# SPDX-License-Identifier: Apache-2.0
# Writes the bash completion of one program from its --help (cmake -P; see
# cmake/Tacse3ManCompletion.cmake): every long option the help names, and the subcommands CLI11
# lists under "Subcommands:". Words that are not options complete as file names.
#   cmake -DPROGRAM=path -DNAME=tacse3-x [-DEMULATOR=qemu;-L;root] -DOUT=file -P tacse3_completion.cmake
execute_process(COMMAND ${EMULATOR} "${PROGRAM}" --help OUTPUT_VARIABLE help RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${NAME} --help failed (${rc})")
endif()
string(REGEX MATCHALL "--[a-z][a-z0-9-]*" options "${help}")
list(REMOVE_DUPLICATES options)
list(SORT options)
set(subcommands "")
string(FIND "${help}" "Subcommands:" at)
if(NOT at EQUAL -1)
  string(SUBSTRING "${help}" ${at} -1 tail)
  string(REGEX MATCHALL "\n  [a-z][a-z0-9-]*" words "${tail}")
  foreach(w IN LISTS words)
    string(STRIP "${w}" w)
    list(APPEND subcommands "${w}")
  endforeach()
endif()
if(NOT options)
  message(FATAL_ERROR "${NAME} --help names no options")
endif()
list(JOIN options " " options)
list(JOIN subcommands " " subcommands)
string(MAKE_C_IDENTIFIER "_${NAME}" fn)
file(WRITE "${OUT}" "# bash completion for ${NAME}, generated from its --help (cmake/tacse3_completion.cmake).
${fn}() {
  local cur=\"\${COMP_WORDS[COMP_CWORD]}\"
  if [[ \"\$cur\" == -* ]]; then
    COMPREPLY=(\$(compgen -W \"${options}\" -- \"\$cur\"))
  else
    COMPREPLY=(\$(compgen -W \"${subcommands}\" -- \"\$cur\"))
  fi
}
complete -o default -F ${fn} ${NAME}
")
