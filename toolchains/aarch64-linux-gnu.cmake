# SPDX-License-Identifier: Apache-2.0
# Cross toolchain for 64-bit Raspberry Pi class boards (Cortex-A72/A76), Debian's
# g++-aarch64-linux-gnu. Tests run on x86 through qemu-user with the cross sysroot.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(TACSE3_TRIPLE aarch64-linux-gnu)
set(CMAKE_C_COMPILER ${TACSE3_TRIPLE}-gcc)
set(CMAKE_CXX_COMPILER ${TACSE3_TRIPLE}-g++)
set(TACSE3_CROSS_SYSROOT "/usr/${TACSE3_TRIPLE}" CACHE PATH "Target runtime root used by qemu-user")
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64-static -L ${TACSE3_CROSS_SYSROOT})
# Tune for the Raspberry Pi 4 core; the code stays valid on any ARMv8-A.
set(CMAKE_C_FLAGS_INIT "-mcpu=cortex-a72")
set(CMAKE_CXX_FLAGS_INIT "-mcpu=cortex-a72")
set(CMAKE_FIND_ROOT_PATH "${TACSE3_CROSS_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
