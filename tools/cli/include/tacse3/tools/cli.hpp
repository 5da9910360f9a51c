// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: command-line rules shared by the CLI11 tools (header-only, target
// tacse3_tools_cli).
#pragma once

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include "tacse3/version.hpp"

namespace tacse3::tools {

// For every option that takes a path: an empty value is a usage error naming the option. It must
// never mean "no file" (`--calibration ''` would run with the defaults without a word).
inline CLI::Validator non_empty_path() {
  return CLI::Validator(
      [](std::string& v) {
        return v.empty() ? std::string("empty path; give a file name or leave the option out")
                         : std::string();
      },
      "");
}

// The program's name: argv[0] without its folder.
inline std::string program_name(const char* argv0) {
  std::string name = argv0 != nullptr ? argv0 : "tacse3";
  if (const auto slash = name.rfind('/'); slash != std::string::npos) name.erase(0, slash + 1);
  return name;
}

// Parses the command line. Returns -1 to go on, else the exit code: 0 after --help or
// --version, 2 for a usage error (the same as tacse3d). --version prints "NAME VERSION", the
// line help2man reads; the usage line names the program without its folder.
inline int parse_command_line(CLI::App& app, int argc, char** argv) {
  const std::string name = program_name(argc > 0 ? argv[0] : nullptr);
  if (app.get_name().empty()) app.name(name);
  app.set_version_flag("--version", name + " " + kVersion,
                       "print the program's name and version and exit");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  return -1;
}

// Flushes and closes standard output at the end of a tool: results that did not arrive (a full
// disk, /dev/full) must not end in exit 0. Returns rc, or 1 if rc is 0 and a write failed.
inline int finish_stdout(const char* tool, int rc) {
  errno = 0;
  bool ok = std::fflush(stdout) == 0 && std::ferror(stdout) == 0;
  const int e = errno;  // set when the last flush failed; an earlier failed write left only ferror
  ok = std::fclose(stdout) == 0 && ok;
  if (ok) return rc;
  const std::string why = e != 0 ? std::string(" (") + std::strerror(e) + ")" : std::string();
  std::fprintf(stderr, "%s: error: standard output: write error%s; the output is incomplete\n",
               tool, why.c_str());
  return rc != 0 ? rc : 1;
}

}  // namespace tacse3::tools
