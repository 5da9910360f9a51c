# SPDX-License-Identifier: Apache-2.0
# Project-wide warning set, applied per target with tacse3_warnings(<target>).
function(tacse3_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wshadow -Wdouble-promotion
                                           -Wnon-virtual-dtor -Wcast-align -Wnull-dereference
                                           -Wimplicit-fallthrough)
  if(TACSE3_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
