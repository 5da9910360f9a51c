# SPDX-License-Identifier: Apache-2.0
# tacse3: finds third-party libraries (pkg-config) on the build host or in a cross target sysroot.
#
# Native builds use the system's pkg-config files. Cross builds look in TACSE3_TARGET_SYSROOT,
# a directory made by scripts/make-sysroot.sh <arch> (target .debs unpacked with dpkg -x); its
# default is build/sysroot/<aarch64|armhf> in the source tree. Nothing there: the library is
# reported missing and whatever needs it is skipped by its caller.
#
# Included once from the top-level CMakeLists.txt before the subdirectories; including it again
# (hal/camera/cmake/Tacse3HalDeps.cmake forwards here) is harmless. Everything the function needs
# lives in cache entries, not directory variables, so it works from any directory that calls it.
include_guard(GLOBAL)

get_filename_component(_tacse3_deps_repo "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
if(CMAKE_CROSSCOMPILING)
  # The sysroot folder name scripts/make-sysroot.sh uses for this target.
  if(CMAKE_SYSTEM_PROCESSOR MATCHES "^(aarch64|arm64|ARM64)$")
    set(_tacse3_deps_arch aarch64)
  elseif(CMAKE_SYSTEM_PROCESSOR MATCHES "^arm")
    set(_tacse3_deps_arch armhf)
  else()
    set(_tacse3_deps_arch "${CMAKE_SYSTEM_PROCESSOR}")
  endif()
  set(TACSE3_TARGET_ARCH_DIR "${_tacse3_deps_arch}" CACHE INTERNAL "build/sysroot/<name> of this target")
  set(TACSE3_TARGET_SYSROOT "${_tacse3_deps_repo}/build/sysroot/${_tacse3_deps_arch}" CACHE PATH
      "Target root with the -dev packages unpacked (scripts/make-sysroot.sh <arch>)")
  if(TACSE3_TRIPLE)
    set(TACSE3_TARGET_MULTIARCH "${TACSE3_TRIPLE}" CACHE STRING "Debian multiarch triple of the target")
  elseif(CMAKE_LIBRARY_ARCHITECTURE)
    set(TACSE3_TARGET_MULTIARCH "${CMAKE_LIBRARY_ARCHITECTURE}" CACHE STRING "Debian multiarch triple of the target")
  else()
    set(TACSE3_TARGET_MULTIARCH "${CMAKE_SYSTEM_PROCESSOR}-linux-gnu" CACHE STRING "Debian multiarch triple of the target")
  endif()
else()
  set(TACSE3_TARGET_SYSROOT "" CACHE PATH
      "Target root with the -dev packages (cross builds; empty = the build host's system)")
endif()

# tacse3_find_pkg(<target> <pkg-config modules...> [MIN_VERSION <v>])
# Defines the INTERFACE IMPORTED GLOBAL target <target> (full library paths, SYSTEM includes)
# when every module is found; sets <target>_FOUND, <target>_VERSION (first module) and
# <target>_WHY (the reason when not found) in the caller's scope. Calling it again for the same
# <target> (from another directory) reuses the target.
function(tacse3_find_pkg target)
  cmake_parse_arguments(ARG "" "MIN_VERSION" "" ${ARGN})
  set(modules ${ARG_UNPARSED_ARGUMENTS})
  set(${target}_FOUND FALSE PARENT_SCOPE)
  if(TARGET ${target})
    set(${target}_FOUND TRUE PARENT_SCOPE)
    get_target_property(v ${target} TACSE3_VERSION)
    set(${target}_VERSION "${v}" PARENT_SCOPE)
    return()
  endif()
  # In the function's scope, so callers in directories that never included this file (it has a
  # global include guard) still get FindPkgConfig's directory variables; the lookup is cached.
  find_package(PkgConfig QUIET)
  if(NOT PKG_CONFIG_FOUND)
    set(${target}_WHY "pkg-config not installed" PARENT_SCOPE)
    return()
  endif()

  set(sysroot "${TACSE3_TARGET_SYSROOT}")
  set(multiarch "${TACSE3_TARGET_MULTIARCH}")
  set(libdirs "")
  if(CMAKE_CROSSCOMPILING)
    if(NOT sysroot OR NOT IS_DIRECTORY "${sysroot}")
      set(${target}_WHY "no target sysroot at '${sysroot}' (run scripts/make-sysroot.sh ${TACSE3_TARGET_ARCH_DIR})"
          PARENT_SCOPE)
      return()
    endif()
    set(libdirs "${sysroot}/usr/lib/${multiarch}" "${sysroot}/lib/${multiarch}")
    set(saved_libdir "$ENV{PKG_CONFIG_LIBDIR}")
    set(saved_path "$ENV{PKG_CONFIG_PATH}")
    set(saved_sysroot "$ENV{PKG_CONFIG_SYSROOT_DIR}")
    set(ENV{PKG_CONFIG_LIBDIR} "${sysroot}/usr/lib/${multiarch}/pkgconfig:${sysroot}/usr/share/pkgconfig")
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

  # Resolve every -l to a full path, in the sysroot only when cross compiling (the toolchain's
  # CMAKE_FIND_ROOT_PATH is the cross libc root, which does not hold these libraries).
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
    # The multiarch folder too: the native compiler searches /usr/include/<triple> by itself, the
    # cross one not in the sysroot (OpenSSL's opensslconf.h, which cpp-httplib's header reaches).
    list(APPEND includes "${sysroot}/usr/include" "${sysroot}/usr/include/${multiarch}")
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
    # The sysroot's libraries pull further libraries (libcamera: libyaml, libudev, gnutls...;
    # libsystemd: libcap, libgcrypt, lz4, zstd): let the linker find them there. Build-tree
    # executables get the sysroot library folder in their RPATH from CMake (the libraries above
    # are linked by full path); --disable-new-dtags makes it a DT_RPATH, which, unlike DT_RUNPATH,
    # also serves those indirect libraries, so the binaries run under qemu-user (whose -L prefix
    # is the cross libc root: an absolute RPATH that does not exist under it falls back to the
    # host path). Installed binaries (cmake --install, the .deb) get the empty install RPATH.
    set_property(TARGET ${target} PROPERTY INTERFACE_LINK_OPTIONS
      "LINKER:-rpath-link,${sysroot}/usr/lib/${multiarch}"
      "LINKER:-rpath-link,${sysroot}/lib/${multiarch}"
      "LINKER:--disable-new-dtags")
  endif()
  set_property(GLOBAL APPEND PROPERTY TACSE3_FOUND_PKG_TARGETS ${target})
  set(${target}_FOUND TRUE PARENT_SCOPE)
  set(${target}_VERSION "${version}" PARENT_SCOPE)
endfunction()

# The name hal/camera, hal/gpio and the daemon were written against. A macro, so the results
# tacse3_find_pkg sets in its caller's scope land in the caller of tacse3_hal_find_pkg.
macro(tacse3_hal_find_pkg)
  tacse3_find_pkg(${ARGV})
endmacro()

# toml++ (Debian's libtomlplusplus-dev, header-only, used without exceptions) as the INTERFACE
# target tacse3_dep_tomlpp, defined once for the calibration and board readers (config/) and the
# tools. Cross builds take the host's headers through a folder
# holding only a link to them, so the rest of /usr/include stays out of the target's include path.
# No toml++: no target, and the callers skip what needs it.
function(tacse3_find_tomlpp)
  if(TARGET tacse3_dep_tomlpp)
    return()
  endif()
  find_path(TACSE3_TOMLPP_INCLUDE_DIR toml++/toml.h)
  set(dir "${TACSE3_TOMLPP_INCLUDE_DIR}")
  if(NOT dir AND CMAKE_CROSSCOMPILING)
    find_path(TACSE3_TOMLPP_HOST_INCLUDE_DIR toml++/toml.h PATHS /usr/include
              NO_CMAKE_FIND_ROOT_PATH NO_DEFAULT_PATH)
    if(TACSE3_TOMLPP_HOST_INCLUDE_DIR)
      set(dir "${CMAKE_BINARY_DIR}/_tomlpp/include")
      file(MAKE_DIRECTORY "${dir}")
      if(NOT EXISTS "${dir}/toml++")
        file(CREATE_LINK "${TACSE3_TOMLPP_HOST_INCLUDE_DIR}/toml++" "${dir}/toml++" SYMBOLIC)
      endif()
    endif()
  endif()
  if(dir)
    add_library(tacse3_dep_tomlpp INTERFACE IMPORTED GLOBAL)  # imported: a SYSTEM include
    set_target_properties(tacse3_dep_tomlpp PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${dir}")
  endif()
endfunction()

# tacse3_link_if_target(TARGET DEP DEFINE SCOPE): links DEP into TARGET (PUBLIC) and defines
# DEFINE=1 with SCOPE (PUBLIC or PRIVATE) when DEP is built in this tree, DEFINE=0 otherwise: the
# optional backends the daemon compiles in or reports as missing.
function(tacse3_link_if_target target dep define scope)
  if(TARGET ${dep})
    target_link_libraries(${target} PUBLIC ${dep})
    target_compile_definitions(${target} ${scope} ${define}=1)
  else()
    target_compile_definitions(${target} ${scope} ${define}=0)
  endif()
endfunction()
