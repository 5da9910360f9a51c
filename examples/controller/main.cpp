// SPDX-License-Identifier: Apache-2.0
// tacse3 example: a controller loop that decodes tacse3 frames and applies the residual correction.
//
// Build against an installed tacse3 (find_package(tacse3 COMPONENTS protocol)) or in-tree.
// Input: candump -L lines on stdin or from a file (on a robot: frames from your CAN driver).
// Output: CSV, one row per complete cycle: t_us, counter, theta_hat (rad, gripper frame G),
// a_base (6), a_corr (6).
//
//   tacse3-controller-example --log bus.log --gain 1.0
//   candump -L can0 | tacse3-controller-example --log - --node 1
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "residual.hpp"
#include "tacse3/protocol/protocol.hpp"

namespace tp = tacse3::protocol;
namespace ex = tacse3::example;

namespace {

constexpr std::size_t kActionDim = 6;  // end-effector step [dx dy dz drx dry drz]
using PostProcessor = ex::ResidualPostProcessor<kActionDim>;

void usage() {
  std::fprintf(stderr,
               "usage: tacse3-controller-example [--log FILE|-] [--node N] [--extended]\n"
               "         [--source pose|twist] [--gain K | --gamma \"r1;r2;r3;r4;r5;r6\"]\n"
               "         [--max-step-deg D]\n"
               "  --gain K   Gamma = [0; -K*I]: counter-rotate the end effector by K * theta_hat\n"
               "  --gamma    six rows of three comma-separated numbers (Gamma is 6 x 3)\n");
}

// The nominal action stream of a base policy: here a slow planar circle (the paper's "Drawing"
// task) with no rotation. A real controller takes a_base from its policy.
PostProcessor::Action base_action(double t) {
  const double w = 2.0 * M_PI * 0.2;
  const double r = 0.05;
  const double dt = 1.0 / 120.0;
  return {-r * w * std::sin(w * t) * dt, r * w * std::cos(w * t) * dt, 0.0, 0.0, 0.0, 0.0};
}

bool parse_gamma(const std::string& s, PostProcessor::Gamma& g) {
  std::stringstream rows(s);
  std::string row;
  std::size_t i = 0;
  while (std::getline(rows, row, ';')) {
    if (i >= kActionDim) return false;
    std::stringstream cols(row);
    std::string v;
    std::size_t j = 0;
    while (std::getline(cols, v, ',')) {
      if (j >= 3) return false;
      char* end = nullptr;
      g[i][j++] = std::strtod(v.c_str(), &end);
      if (end == v.c_str()) return false;
    }
    if (j != 3) return false;
    ++i;
  }
  return i == kActionDim;
}

}  // namespace

int main(int argc, char** argv) {
  std::string log = "-";
  tp::Endpoint gripper;
  PostProcessor::Config cfg;
  double gain = 1.0;
  std::string gamma;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        usage();
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--log") {
      log = next();
    } else if (a == "--node") {
      gripper.node_id = static_cast<std::uint8_t>(std::atoi(next().c_str()));
    } else if (a == "--extended") {
      gripper.layout.mode = tp::IdMode::kExtended;
    } else if (a == "--source") {
      cfg.source = next() == "twist" ? ex::ThetaSource::kTwist : ex::ThetaSource::kPose;
    } else if (a == "--gain") {
      gain = std::atof(next().c_str());
    } else if (a == "--gamma") {
      gamma = next();
    } else if (a == "--max-step-deg") {
      cfg.max_step_angle_rad = std::atof(next().c_str()) * M_PI / 180.0;
    } else {
      usage();
      return 2;
    }
  }
  if (!tp::is_valid_node_id(gripper.node_id)) {
    std::fprintf(stderr, "tacse3-controller-example: node id must be 1..63\n");
    return 2;
  }
  if (!gamma.empty()) {
    if (!parse_gamma(gamma, cfg.gamma)) {
      std::fprintf(stderr, "tacse3-controller-example: --gamma needs 6 rows of 3 numbers\n");
      return 2;
    }
  } else {
    for (std::size_t k = 0; k < 3; ++k) cfg.gamma[3 + k][k] = -gain;
  }

  std::ifstream file;
  if (log != "-") {
    file.open(log);
    if (!file) {
      std::fprintf(stderr, "tacse3-controller-example: cannot open %s\n", log.c_str());
      return 1;
    }
  }
  std::istream& in = log == "-" ? std::cin : file;

  tp::CycleReassembler reassembler(gripper);
  PostProcessor post(cfg);
  std::printf(
      "t_us,counter,theta_x,theta_y,theta_z,a_base_0,a_base_1,a_base_2,a_base_3,a_base_4,"
      "a_base_5,a_corr_0,a_corr_1,a_corr_2,a_corr_3,a_corr_4,a_corr_5\n");
  std::string line;
  std::uint64_t first_t = 0;
  while (std::getline(in, line)) {
    tp::LogRecord rec;
    if (tp::parse_candump_line(line, rec) != tp::Status::kOk || rec.rtr || rec.error_frame) {
      continue;
    }
    tp::Cycle cycle;
    if (reassembler.feed(rec.frame, cycle) != tp::CycleReassembler::Result::kComplete) continue;
    // Here the controller runs once per tacse3 cycle; a slower loop would call observe() for
    // every cycle and step() once per control period.
    post.observe(cycle);
    if (first_t == 0) first_t = cycle.timestamp_us;
    const double t = static_cast<double>(cycle.timestamp_us - first_t) * 1e-6;
    const PostProcessor::Action a_base = base_action(t);
    tp::Vec3 theta;
    const PostProcessor::Action a_corr = post.step(a_base, &theta);
    std::printf("%llu,%u,%.6f,%.6f,%.6f", static_cast<unsigned long long>(cycle.timestamp_us),
                unsigned{cycle.counter}, theta.x, theta.y, theta.z);
    for (double v : a_base) std::printf(",%.6f", v);
    for (double v : a_corr) std::printf(",%.6f", v);
    std::printf("\n");
  }
  const tp::ReassemblerStats& s = reassembler.stats();
  std::fprintf(stderr,
               "tacse3-controller-example: node %u: %u cycles, %u counter gaps, %u CRC errors, "
               "%u incomplete, %llu clamped steps\n",
               unsigned{gripper.node_id}, s.samples, s.counter_gaps, s.crc_errors, s.incomplete,
               static_cast<unsigned long long>(post.clamped_steps()));
  return 0;
}
