# SPDX-License-Identifier: Apache-2.0
# tacse3 hal: forwarder kept for the hal folders and the daemon that include this path.
#
# The target-dependency lookup (host pkg-config or the cross sysroot of scripts/make-sysroot.sh)
# moved to cmake/Tacse3TargetDeps.cmake, which the top-level CMakeLists.txt includes before the
# subdirectories. Including this file still works on its own and defines the same functions:
# tacse3_find_pkg(<target> <modules...> [MIN_VERSION v]) and its old name tacse3_hal_find_pkg.
include("${CMAKE_CURRENT_LIST_DIR}/../../../cmake/Tacse3TargetDeps.cmake")
