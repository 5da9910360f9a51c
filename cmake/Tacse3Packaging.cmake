# SPDX-License-Identifier: Apache-2.0
# tacse3: CPack .deb of the daemon, the tools, the boards, the systemd/udev/networkd files and the
# default /etc/tacse3 config (docs/install.md). One package per target architecture:
#   cmake --preset aarch64 -B build/x -DTACSE3_BUILD_TESTS=OFF
#   cmake --build build/x --target tacse3_package_programs && cpack --config build/x/CPackConfig.cmake
# scripts/package.sh does exactly that for arm64 and armhf and checks the result.
#
# Everything goes into the install component "tacse3_deb", marked EXCLUDE_FROM_ALL: a plain
# `cmake --install` is unchanged (no /etc writes on a developer machine), and the package holds
# only what is listed here, never the tests, benchmarks or the protocol's development files.
# Included at the end of the top-level CMakeLists.txt, after every target exists.
include_guard(GLOBAL)
include(GNUInstallDirs)

set(_tacse3_pkg_src "${PROJECT_SOURCE_DIR}/packaging")
set(_tacse3_pkg_comp tacse3_deb)

# Programs shipped in /usr/bin, each when its target exists in this configuration. Not shipped:
# tacse3-dbcgen (the generated DBC itself is in /usr/share/tacse3) and tacse3-bench-accuracy
# (the paper's accuracy tables, a development benchmark).
set(TACSE3_PACKAGE_PROGRAMS
    tacse3d tacse3-canmon tacse3-ctl tacse3-replay tacse3-calibrate tacse3-truth tacse3-sim
    tacse3-demo
    CACHE STRING "Executable targets installed by the .deb when they exist")

set(_tacse3_pkg_programs "")
foreach(program IN LISTS TACSE3_PACKAGE_PROGRAMS)
  if(TARGET ${program})
    list(APPEND _tacse3_pkg_programs ${program})
  endif()
endforeach()
if(_tacse3_pkg_programs)
  # install(TARGETS) rewrites the build-tree RPATH (which points into build/sysroot for qemu) to
  # the empty install RPATH: the board's loader finds the libraries in the system paths.
  install(TARGETS ${_tacse3_pkg_programs} RUNTIME DESTINATION "${CMAKE_INSTALL_BINDIR}"
          COMPONENT ${_tacse3_pkg_comp} EXCLUDE_FROM_ALL)
endif()
# Builds just what the package holds (no tests, no benchmarks).
add_custom_target(tacse3_package_programs)
if(_tacse3_pkg_programs)
  add_dependencies(tacse3_package_programs ${_tacse3_pkg_programs})
endif()

# Manual pages (help2man) and bash completion, from the programs' --help and --version.
include(Tacse3ManCompletion)
if(_tacse3_pkg_programs)
  tacse3_man_completion(${_tacse3_pkg_programs})
  add_dependencies(tacse3_package_programs tacse3_man_completion)
  if(NOT TACSE3_HELP2MAN)
    # The package ships a manual page per program: without help2man it cannot be made.
    add_custom_target(tacse3_need_help2man
      COMMAND "${CMAKE_COMMAND}" -E echo "the .deb needs help2man for its manual pages: apt-get install help2man, then configure again"
      COMMAND "${CMAKE_COMMAND}" -E false
      VERBATIM)
    add_dependencies(tacse3_package_programs tacse3_need_help2man)
  endif()
  if(TACSE3_MAN_PAGES)
    install(FILES ${TACSE3_MAN_PAGES} DESTINATION "${CMAKE_INSTALL_DATADIR}/man/man1"
            COMPONENT ${_tacse3_pkg_comp} EXCLUDE_FROM_ALL)
  endif()
  install(FILES ${TACSE3_COMPLETIONS} DESTINATION "${CMAKE_INSTALL_DATADIR}/bash-completion/completions"
          COMPONENT ${_tacse3_pkg_comp} EXCLUDE_FROM_ALL)
endif()

# Boards: /usr/share/tacse3/boards/<name>/board.toml, the daemon's <exe_dir>/../share lookup.
file(GLOB _tacse3_pkg_boards CONFIGURE_DEPENDS "${PROJECT_SOURCE_DIR}/boards/*/board.toml")
foreach(board_file IN LISTS _tacse3_pkg_boards)
  get_filename_component(board_dir "${board_file}" DIRECTORY)
  get_filename_component(board "${board_dir}" NAME)
  install(FILES "${board_file}" DESTINATION "${CMAKE_INSTALL_DATADIR}/tacse3/boards/${board}"
          COMPONENT ${_tacse3_pkg_comp} EXCLUDE_FROM_ALL)
endforeach()
# The live view's page (docs/viewer.md): /usr/share/tacse3/viewer, the daemon's
# <exe_dir>/../share lookup, when this tacse3d is built with the viewer.
if(TARGET tacse3_viewer_assets)
  install(DIRECTORY "${TACSE3_VIEWER_DIR}/" DESTINATION "${CMAKE_INSTALL_DATADIR}/tacse3/viewer"
          COMPONENT ${_tacse3_pkg_comp} EXCLUDE_FROM_ALL)
  add_dependencies(tacse3_package_programs tacse3_viewer_assets)
  # The drop-in that opens the unit to IPv4 for it, for the integrator to enable.
  install(FILES "${_tacse3_pkg_src}/viewer-network.conf" DESTINATION "${CMAKE_INSTALL_DATADIR}/tacse3/systemd"
          COMPONENT ${_tacse3_pkg_comp} EXCLUDE_FROM_ALL)
endif()
# The simulator's calibration: tacse3d --board sim and tacse3-replay of a simulator recording
# use it when no --calibration is given (config::find_sim_calibration).
install(FILES "${PROJECT_SOURCE_DIR}/tools/replay/data/sim-calibration.toml"
        DESTINATION "${CMAKE_INSTALL_DATADIR}/tacse3" COMPONENT ${_tacse3_pkg_comp} EXCLUDE_FROM_ALL)
if(EXISTS "${PROJECT_SOURCE_DIR}/protocol/tacse3.dbc")
  install(FILES "${PROJECT_SOURCE_DIR}/protocol/tacse3.dbc" DESTINATION "${CMAKE_INSTALL_DATADIR}/tacse3"
          COMPONENT ${_tacse3_pkg_comp} EXCLUDE_FROM_ALL)
endif()

# systemd, udev and networkd read /usr/lib (the package's defaults) and /etc (the admin's, which
# win for the same file name). Relative destinations land under CPACK_PACKAGING_INSTALL_PREFIX.
install(FILES "${_tacse3_pkg_src}/tacse3d.service" DESTINATION lib/systemd/system
        COMPONENT ${_tacse3_pkg_comp} EXCLUDE_FROM_ALL)
install(FILES "${_tacse3_pkg_src}/tacse3d.sysusers" DESTINATION lib/sysusers.d RENAME tacse3d.conf
        COMPONENT ${_tacse3_pkg_comp} EXCLUDE_FROM_ALL)
install(FILES "${_tacse3_pkg_src}/udev/60-tacse3-gpio.rules" DESTINATION lib/udev/rules.d
        COMPONENT ${_tacse3_pkg_comp} EXCLUDE_FROM_ALL)
install(FILES "${_tacse3_pkg_src}/network/80-tacse3-can0.network" DESTINATION lib/systemd/network
        COMPONENT ${_tacse3_pkg_comp} EXCLUDE_FROM_ALL)
install(FILES "${_tacse3_pkg_src}/network/80-tacse3-can0-fd.network"
        DESTINATION "${CMAKE_INSTALL_DATADIR}/tacse3/network" COMPONENT ${_tacse3_pkg_comp} EXCLUDE_FROM_ALL)
if(EXISTS "${PROJECT_SOURCE_DIR}/docs/install.md")
  install(FILES "${PROJECT_SOURCE_DIR}/docs/install.md" DESTINATION "${CMAKE_INSTALL_DATADIR}/doc/tacse3"
          COMPONENT ${_tacse3_pkg_comp} EXCLUDE_FROM_ALL)
endif()

# Configuration files the admin edits: in /etc and listed in conffiles, so updates keep the edits.
set(_tacse3_pkg_conffiles
    /etc/tacse3/tacse3d.conf
    /etc/tacse3/calibration.toml
    /etc/udev/rules.d/61-tacse3-cameras.rules)
install(FILES "${_tacse3_pkg_src}/tacse3d.conf" "${_tacse3_pkg_src}/calibration.toml"
        DESTINATION /etc/tacse3 COMPONENT ${_tacse3_pkg_comp} EXCLUDE_FROM_ALL)
install(FILES "${_tacse3_pkg_src}/udev/61-tacse3-cameras.rules" DESTINATION /etc/udev/rules.d
        COMPONENT ${_tacse3_pkg_comp} EXCLUDE_FROM_ALL)

# Debian architecture of this build.
if(CMAKE_SYSTEM_PROCESSOR MATCHES "^(aarch64|arm64|ARM64)$")
  set(_tacse3_deb_arch arm64)
elseif(CMAKE_SYSTEM_PROCESSOR MATCHES "^arm")
  set(_tacse3_deb_arch armhf)
elseif(CMAKE_SYSTEM_PROCESSOR MATCHES "^(x86_64|AMD64|amd64)$")
  set(_tacse3_deb_arch amd64)
else()
  set(_tacse3_deb_arch "${CMAKE_SYSTEM_PROCESSOR}")
endif()

set(_tacse3_pkg_gen "${CMAKE_BINARY_DIR}/packaging")
file(MAKE_DIRECTORY "${_tacse3_pkg_gen}")
string(JOIN "\n" _tacse3_conffiles_text ${_tacse3_pkg_conffiles})
file(WRITE "${_tacse3_pkg_gen}/conffiles" "${_tacse3_conffiles_text}\n")
# The maintainer scripts must be executable inside the package (dpkg runs them directly).
file(COPY "${_tacse3_pkg_src}/deb/postinst" "${_tacse3_pkg_src}/deb/prerm" "${_tacse3_pkg_src}/deb/postrm"
     DESTINATION "${_tacse3_pkg_gen}"
     FILE_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE WORLD_READ WORLD_EXECUTE)
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS
             "${_tacse3_pkg_src}/deb/postinst" "${_tacse3_pkg_src}/deb/prerm" "${_tacse3_pkg_src}/deb/postrm")

# Depends is derived at cpack time from what the built binaries link (DT_NEEDED) through the
# hand-kept table packaging/deb/shlibs.txt: dpkg-shlibdeps cannot run on a foreign architecture
# without the target's dpkg database. The list of binaries is known only at generate time.
set(_tacse3_pkg_files "")
foreach(program IN LISTS _tacse3_pkg_programs)
  string(APPEND _tacse3_pkg_files "$<TARGET_FILE:${program}>\n")
endforeach()
file(GENERATE OUTPUT "${_tacse3_pkg_gen}/binaries.txt" CONTENT "${_tacse3_pkg_files}")
if(CMAKE_READELF)
  set(_tacse3_readelf "${CMAKE_READELF}")
else()
  find_program(_tacse3_readelf NAMES readelf REQUIRED)
endif()
file(WRITE "${_tacse3_pkg_gen}/CPackProjectConfig.cmake" "\
# Generated by cmake/Tacse3Packaging.cmake: Depends from the binaries' DT_NEEDED at cpack time.
set(_readelf \"${_tacse3_readelf}\")
set(_shlibs \"${_tacse3_pkg_src}/deb/shlibs.txt\")
set(_binaries \"${_tacse3_pkg_gen}/binaries.txt\")
include(\"${_tacse3_pkg_src}/deb/depends.cmake\")
")

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME tacse3)
set(CPACK_PACKAGE_VERSION "${PROJECT_VERSION}")
set(CPACK_PACKAGE_VENDOR "tacse3")
set(CPACK_PACKAGE_CONTACT "tacse3 developers <tacse3@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "tactile SE(3) motion estimation firmware for a dual DM-Tac gripper")
# Debian shows the long description as is: lines of at most 80 columns.
string(JOIN "\n" CPACK_PACKAGE_DESCRIPTION
  "tacse3d reads two mirrored vision-based tactile sensors, runs the fixed-point"
  "TacSE3 pipeline and streams twist and pose over CAN. The package holds the"
  "daemon with its systemd service, the board files, the udev and systemd-networkd"
  "configuration, and the command-line tools (tacse3-canmon, tacse3-ctl,"
  "tacse3-replay, tacse3-calibrate, tacse3-truth, tacse3-sim, tacse3-demo).")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
# Only the package component, into one package (a monolithic .deb with a component filter).
set(CPACK_INSTALL_CMAKE_PROJECTS "${CMAKE_BINARY_DIR};${PROJECT_NAME};${_tacse3_pkg_comp};/")
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_PACKAGE_NAME tacse3)
set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE "${_tacse3_deb_arch}")
set(CPACK_DEBIAN_FILE_NAME "tacse3_${PROJECT_VERSION}_${_tacse3_deb_arch}.deb")
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "can-utils")
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS OFF)
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    "${_tacse3_pkg_gen}/conffiles" "${_tacse3_pkg_gen}/postinst" "${_tacse3_pkg_gen}/prerm"
    "${_tacse3_pkg_gen}/postrm")
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(CPACK_PROJECT_CONFIG_FILE "${_tacse3_pkg_gen}/CPackProjectConfig.cmake")
set(CPACK_OUTPUT_FILE_PREFIX "${CMAKE_BINARY_DIR}/deb")
include(CPack)
