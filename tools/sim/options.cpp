// SPDX-License-Identifier: Apache-2.0
// tacse3-sim: command-line parsing with CLI11 (kept in its own file: GCC 12 reports a false
// -Wnull-dereference inside CLI11's inlined std::string code, so this file disables it).
#include "options.hpp"

#include <CLI/CLI.hpp>

#include "tacse3/sim/object.hpp"
#include "tacse3/sim/profile.hpp"
#include "tacse3/tools/cli.hpp"

namespace tacse3::tools {

int parse_options(int argc, char** argv, Options* o) {
  CLI::App app{
      "tacse3-sim: render a simulated grasp of an object between two mirrored DM-Tac sensors,\n"
      "then a commanded motion and a hold, as a recording directory with truth.csv\n"
      "(docs/simulator.md, docs/recording-format.md)."};
  app.add_option("-o,--out", o->out, "Output recording directory (required unless --profile list)")
      ->check(non_empty_path());
  app.add_option("--object", o->object,
                 std::string("Object preset: ") + tacse3::sim::object_preset_names())
      ->capture_default_str();
  app.add_option("--motion", o->motion,
                 "Commanded motion: rx, ry, rz (rotation about G's axis) or tx, ty")
      ->capture_default_str();
  app.add_option(
      "--magnitude", o->magnitude,
      "Motion magnitude: degrees (rotations) or mm (translations); default 30 deg / 10 mm");
  app.add_option("--regime", o->regime,
                 "Tangential regime: stick, slide, or auto (stick up to 5 deg / 1 mm)")
      ->capture_default_str();
  app.add_option("--profile", o->profile,
                 std::string("Sensor profile (docs/sim-profiles.md): ") +
                     tacse3::sim::profile_names() +
                     "; random:N, the random profile's sensor N in every recording; \"list\" "
                     "prints them with their values")
      ->capture_default_str();
  app.add_option("--seed", o->seed,
                 "Seed of the pattern, noise, flicker, bumpy shape and the random profile")
      ->capture_default_str();
  app.add_option("--noise", o->noise, "Sensor noise multiplier, 0 = noiseless (default 1)");
  app.add_option("--flicker", o->flicker,
                 "Peak per-frame global gain flicker, 0.02 = +-2% (default: the profile's)");
  auto* radius = app.add_option(
      "--radius", o->radius, "Object size in mm: half-width along the grasp axis (preset default)");
  app.add_option("--finger-separation", o->separation,
                 "Scale the object so the pads end the grasp this far apart (mm)")
      ->excludes(radius);
  app.add_option("--indentation", o->indentation,
                 "Peak gel indentation after the grasp in mm (default: the profile's)");
  app.add_option("--pixel-pitch", o->pitch,
                 "Pixel pitch P on the pad in mm/px (default: the profile's)");
  app.add_option("--friction", o->friction, "Object-gel friction coefficient (preset default)");
  app.add_option("--offset", o->offset, "Object centre offset in G x y at the first frame (mm)")
      ->expected(2);
  app.add_option("--approach-s", o->approach_s, "Pads open, no contact (s)")->capture_default_str();
  app.add_option("--grasp-s", o->grasp_s, "Pads closing, indentation ramp (s)")
      ->capture_default_str();
  app.add_option("--settle-s", o->settle_s, "Static grasp before the motion (s)")
      ->capture_default_str();
  app.add_option("--motion-s", o->motion_s,
                 "Motion duration (s); 0 = the profile's speed, or auto from the magnitude")
      ->capture_default_str();
  app.add_option("--hold-s", o->hold_s, "Static hold after the motion (s)")->capture_default_str();
  app.add_option("--release-s", o->release_s,
                 "Pads opening after the hold, contact lost (s); 0 = none")
      ->capture_default_str();
  app.add_option("--fps", o->fps, "Frame rate")->capture_default_str();
  app.add_option("--sensors", o->sensors, "Sensors to record: both, left or right")
      ->capture_default_str();
  app.add_option("--colour", o->colour, "Frame format: rgb or grey")->capture_default_str();
  app.add_option("--png-level", o->png_level, "PNG zlib level 0..9")->capture_default_str();
  app.add_option("-j,--jobs", o->jobs, "Threads (1, or 2: one per sensor)")->capture_default_str();
  app.add_flag("--overwrite", o->overwrite, "Replace an existing recording in --out");
  app.add_flag("-q,--quiet", o->quiet, "No progress bar and no summary");
  return parse_command_line(app, argc, argv);
}

}  // namespace tacse3::tools
