# SPDX-License-Identifier: Apache-2.0
# Cross toolchain for 32-bit Raspberry Pi OS (armhf, ARMv7-A with VFPv3-D16 hard float),
# Debian's g++-arm-linux-gnueabihf. Tests run on x86 through qemu-user with the cross sysroot.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR armv7l)
set(TACSE3_TRIPLE arm-linux-gnueabihf)
set(CMAKE_C_COMPILER ${TACSE3_TRIPLE}-gcc)
set(CMAKE_CXX_COMPILER ${TACSE3_TRIPLE}-g++)
set(TACSE3_CROSS_SYSROOT "/usr/${TACSE3_TRIPLE}" CACHE PATH "Target runtime root used by qemu-user")
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-arm-static -L ${TACSE3_CROSS_SYSROOT})
set(CMAKE_FIND_ROOT_PATH "${TACSE3_CROSS_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
