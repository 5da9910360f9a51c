// SPDX-License-Identifier: Apache-2.0
// tacse3-sim: command-line options and their parser.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace tacse3::tools {

struct Options {
  std::string out;
  std::string object = "sphere";
  std::string motion = "rz";
  double magnitude = NAN;
  std::string regime = "auto";
  std::uint64_t seed = 1;
  std::string profile = "reference";
  // NaN: the profile's value.
  double noise = NAN;
  double flicker = NAN;
  double radius = NAN;
  double separation = NAN;
  double indentation = NAN;
  double pitch = NAN;
  double friction = NAN;
  std::vector<double> offset;
  double approach_s = 0.1, grasp_s = 0.4, settle_s = 0.1, motion_s = 0.0, hold_s = 0.4;
  double release_s = 0.0;
  double fps = 120.0;
  std::string sensors = "both";
  std::string colour = "rgb";
  int png_level = 1;
  int jobs = 2;
  bool overwrite = false;
  bool quiet = false;
};

// Parses argv into *o. Returns -1 to go on, or the exit code (0: help shown, 2: a usage error).
int parse_options(int argc, char** argv, Options* o);

}  // namespace tacse3::tools
