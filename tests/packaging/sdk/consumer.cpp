// SPDX-License-Identifier: Apache-2.0
// SDK consumer: decodes the golden TwistAngular frame of docs/can-protocol.md (node 1, 11-bit,
// id 0x022, D2 04 0C FE 30 75 50 89 = ω (1.234, -0.5, 30.0) rad/s) and checks the values, then
// checks that the same frame with one flipped CRC bit is refused. Exit 0 only if both hold.
#include <cmath>
#include <cstdio>
#include <tacse3/protocol/protocol.hpp>
#include <variant>

namespace tp = tacse3::protocol;

int main() {
  tp::CanFrame f;
  f.id = 0x022;
  f.len = 8;
  const std::uint8_t golden[8] = {0xD2, 0x04, 0x0C, 0xFE, 0x30, 0x75, 0x50, 0x89};
  for (std::size_t i = 0; i < 8; ++i) f.data[i] = golden[i];

  tp::Decoded d;
  if (tp::decode(f, tp::IdLayout{}, d) != tp::Status::kOk) {
    std::puts("consumer: the golden frame does not decode");
    return 1;
  }
  const auto* a = std::get_if<tp::AngularMsg>(&d.payload);
  const double want[3] = {1.234, -0.5, 30.0};
  if (a == nullptr || std::fabs(a->angular.x - want[0]) > 1e-9 ||
      std::fabs(a->angular.y - want[1]) > 1e-9 || std::fabs(a->angular.z - want[2]) > 1e-9 ||
      d.node_id != 1) {
    std::puts("consumer: the golden frame decodes to the wrong values");
    return 1;
  }
  const tp::Vec3 w = a->angular;
  const unsigned node = d.node_id;
  f.data[7] ^= 0x01;
  if (tp::decode(f, tp::IdLayout{}, d) == tp::Status::kOk) {
    std::puts("consumer: a frame with a bad CRC was accepted");
    return 1;
  }
  std::printf("consumer: node %u angular %.3f %.3f %.3f rad/s; bad CRC refused\n", node, w.x, w.y,
              w.z);
  return 0;
}
