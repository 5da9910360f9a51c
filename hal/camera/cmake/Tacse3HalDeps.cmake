# SPDX-License-Identifier: Apache-2.0
# tacse3 hal: finds the HAL's third-party libraries (pkg-config) on the host or in a target sysroot.
#
# Native builds use the system's pkg-config files. Cross builds look in TACSE3_TARGET_SYSROOT,
# a directory made by scripts/make-sysroot.sh <arch> (target .debs unpacked with dpkg -x); its
# default is build/sysroot/<aarch64|armhf> in the source tree. Nothing there: the library is
# reported missing and the backend that needs it is skipped.
# Included from each hal folder that needs it (no include guard: it only sets directory-scope
# variables, cache entries and a function, so every including directory sees them).
find_package(PkgConfig QUIET)

get_filename_component(_tacse3_hal_repo "${CMAKE_CURRENT_LIST_DIR}/../../.." ABSOLUTE)
if(CMAKE_CROSSCOMPILING)
  if(CMAKE_SYSTEM_PROCESSOR MATCHES "^(aarch64|arm64|ARM64)$")
    set(_tacse3_hal_arch aarch64)
  elseif(CMAKE_SYSTEM_PROCESSOR MATCHES "^arm")
    set(_tacse3_hal_arch armhf)
  else()
    set(_tacse3_hal_arch "${CMAKE_SYSTEM_PROCESSOR}")
  endif()
  set(TACSE3_TARGET_SYSROOT "${_tacse3_hal_repo}/build/sysroot/${_tacse3_hal_arch}" CACHE PATH
      "Target root with the HAL's -dev packages unpacked (scripts/make-sysroot.sh <arch>)")
  if(TACSE3_TRIPLE)
    set(TACSE3_TARGET_MULTIARCH "${TACSE3_TRIPLE}" CACHE STRING "Debian multiarch triple of the target")
  elseif(CMAKE_LIBRARY_ARCHITECTURE)
    set(TACSE3_TARGET_MULTIARCH "${CMAKE_LIBRARY_ARCHITECTURE}" CACHE STRING "Debian multiarch triple of the target")
  else()
    set(TACSE3_TARGET_MULTIARCH "${CMAKE_SYSTEM_PROCESSOR}-linux-gnu" CACHE STRING "Debian multiarch triple of the target")
  endif()
else()
  set(TACSE3_TARGET_SYSROOT "" CACHE PATH
      "Target root with the HAL's -dev packages (cross builds; empty = the build host's system)")
endif()

# tacse3_hal_find_pkg(<target> <pkg-config modules...> [MIN_VERSION <v>])
# Defines the INTERFACE IMPORTED target <target> (full library paths, SYSTEM includes) when every
# module is found; sets <target>_FOUND, <target>_VERSION (first module) and <target>_WHY (the
# reason when not found) in the caller's scope.
function(tacse3_hal_find_pkg target)
  cmake_parse_arguments(ARG "" "MIN_VERSION" "" ${ARGN})
  set(modules ${ARG_UNPARSED_ARGUMENTS})
  set(${target}_FOUND FALSE PARENT_SCOPE)
  if(TARGET ${target})
    set(${target}_FOUND TRUE PARENT_SCOPE)
    get_target_property(v ${target} TACSE3_VERSION)
    set(${target}_VERSION "${v}" PARENT_SCOPE)
    return()
  endif()
  if(NOT PKG_CONFIG_FOUND)
    set(${target}_WHY "pkg-config not installed" PARENT_SCOPE)
    return()
  endif()

  set(sysroot "${TACSE3_TARGET_SYSROOT}")
  set(libdirs "")
  if(CMAKE_CROSSCOMPILING)
    if(NOT sysroot OR NOT IS_DIRECTORY "${sysroot}")
      set(${target}_WHY "no target sysroot at '${sysroot}' (run scripts/make-sysroot.sh ${_tacse3_hal_arch})" PARENT_SCOPE)
      return()
    endif()
    set(libdirs "${sysroot}/usr/lib/${TACSE3_TARGET_MULTIARCH}" "${sysroot}/lib/${TACSE3_TARGET_MULTIARCH}")
    set(saved_libdir "$ENV{PKG_CONFIG_LIBDIR}")
    set(saved_path "$ENV{PKG_CONFIG_PATH}")
    set(saved_sysroot "$ENV{PKG_CONFIG_SYSROOT_DIR}")
    set(ENV{PKG_CONFIG_LIBDIR} "${sysroot}/usr/lib/${TACSE3_TARGET_MULTIARCH}/pkgconfig:${sysroot}/usr/share/pkgconfig")
    set(ENV{PKG_CONFIG_PATH} "")
    set(ENV{PKG_CONFIG_SYSROOT_DIR} "${sysroot}")
    set(ENV{PKG_CONFIG_ALLOW_SYSTEM_CFLAGS} 1)
    set(ENV{PKG_CONFIG_ALLOW_SYSTEM_LIBS} 1)
  endif()

  string(MAKE_C_IDENTIFIER "_TACSE3_PC_${target}" prefix)
  set(spec ${modules})
  if(ARG_MIN_VERSION)
    list(GET modules 0 first)
    list(REMOVE_AT spec 0)
    list(PREPEND spec "${first}>=${ARG_MIN_VERSION}")
  endif()
  pkg_check_modules(${prefix} QUIET ${spec})

  if(CMAKE_CROSSCOMPILING)
    set(ENV{PKG_CONFIG_LIBDIR} "${saved_libdir}")
    set(ENV{PKG_CONFIG_PATH} "${saved_path}")
    set(ENV{PKG_CONFIG_SYSROOT_DIR} "${saved_sysroot}")
    unset(ENV{PKG_CONFIG_ALLOW_SYSTEM_CFLAGS})
    unset(ENV{PKG_CONFIG_ALLOW_SYSTEM_LIBS})
  endif()
  if(NOT ${prefix}_FOUND)
    string(JOIN " " mods ${spec})
    if(CMAKE_CROSSCOMPILING)
      set(${target}_WHY "pkg-config '${mods}' not found in ${sysroot}" PARENT_SCOPE)
    else()
      set(${target}_WHY "pkg-config '${mods}' not found" PARENT_SCOPE)
    endif()
    return()
  endif()

  # Resolve every -l to a full path, in the sysroot only when cross compiling.
  set(paths "")
  foreach(lib IN LISTS ${prefix}_LIBRARIES)
    string(MAKE_C_IDENTIFIER "TACSE3_HAL_LIB_${target}_${lib}" var)
    if(CMAKE_CROSSCOMPILING)
      find_library(${var} NAMES ${lib} HINTS ${${prefix}_LIBRARY_DIRS} ${libdirs}
                   NO_DEFAULT_PATH NO_CMAKE_FIND_ROOT_PATH)
    else()
      find_library(${var} NAMES ${lib} HINTS ${${prefix}_LIBRARY_DIRS})
    endif()
    if(NOT ${var})
      set(${target}_WHY "library '${lib}' of '${modules}' not found" PARENT_SCOPE)
      return()
    endif()
    list(APPEND paths "${${var}}")
  endforeach()

  set(includes ${${prefix}_INCLUDE_DIRS})
  if(CMAKE_CROSSCOMPILING)
    list(APPEND includes "${sysroot}/usr/include")
  endif()
  list(REMOVE_DUPLICATES includes)

  list(GET modules 0 first_module)
  set(version "${${prefix}_VERSION}")
  if(NOT version)
    set(version "${${prefix}_${first_module}_VERSION}")
  endif()

  add_library(${target} INTERFACE IMPORTED GLOBAL)
  set_target_properties(${target} PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${includes}"
    INTERFACE_LINK_LIBRARIES "${paths}"
    INTERFACE_COMPILE_OPTIONS "${${prefix}_CFLAGS_OTHER}"
    TACSE3_VERSION "${version}")
  if(CMAKE_CROSSCOMPILING)
    # The sysroot's libraries pull further libraries (libcamera: libyaml, libudev, gnutls...):
    # let the linker find them there, and give build-tree executables a DT_RPATH (inherited by
    # those libraries, unlike DT_RUNPATH) so they also run under qemu-user. Installed binaries
    # get the install RPATH instead.
    set_property(TARGET ${target} PROPERTY INTERFACE_LINK_OPTIONS
      "LINKER:-rpath-link,${sysroot}/usr/lib/${TACSE3_TARGET_MULTIARCH}"
      "LINKER:-rpath-link,${sysroot}/lib/${TACSE3_TARGET_MULTIARCH}"
      "LINKER:--disable-new-dtags")
  endif()
  set(${target}_FOUND TRUE PARENT_SCOPE)
  set(${target}_VERSION "${version}" PARENT_SCOPE)
endfunction()
