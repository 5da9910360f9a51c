// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: opendbc-style spam, every 11-bit id and every DLC into the decoders.
#include <gtest/gtest.h>

#include <random>

#include "tacse3/protocol/protocol.hpp"

namespace tp = tacse3::protocol;

namespace {

bool documented(std::uint32_t id, bool fd, std::size_t len) {
  const unsigned node = (id >> 5) & 0x3F;
  const unsigned msg = id & 0x1F;
  if (node == 0) return false;
  const tp::MessageDef* m = tp::find_message(static_cast<std::uint8_t>(msg));
  if (m == nullptr) return false;
  if (m->length != len) return false;
  return fd || !m->fd_only;
}

}  // namespace

// Every 11-bit identifier, every classic DLC and every CAN FD length, random payloads with a
// correct CRC (so only identifier and length decide) and with a random CRC.
TEST(Spam, EveryStandardIdAndLength) {
  std::mt19937 rng(1234);
  std::size_t accepted = 0, accepted_fd = 0, crc_rejected = 0;
  tp::CycleReassembler reasm(tp::Endpoint{});
  tp::CommandReceiver rx(tp::Endpoint{});
  for (std::uint32_t id = 0; id <= 0x7FF; ++id) {
    for (int fd = 0; fd < 2; ++fd) {
      for (int dlc = 0; dlc <= (fd != 0 ? 15 : 8); ++dlc) {
        tp::CanFrame f;
        f.id = id;
        f.fd = fd != 0;
        f.len = fd != 0 ? tp::kFdLengths[static_cast<std::size_t>(dlc)]
                        : static_cast<std::uint8_t>(dlc);
        for (std::size_t i = 0; i < f.len; ++i) f.data[i] = static_cast<std::uint8_t>(rng());
        tp::Decoded d;
        // Random CRC: accepted only when it happens to match.
        const tp::Status s_random = tp::decode(f, tp::IdLayout{}, d);
        if (s_random == tp::Status::kBadCrc) ++crc_rejected;
        if (s_random == tp::Status::kOk) {
          EXPECT_TRUE(documented(id, f.fd, f.len));
        }
        // Correct CRC (and, for CycleFd, agreeing counters): accepted exactly for documented
        // identifier + length combinations.
        if ((id & 0x1F) == 0x06 && f.len == 64) {
          for (std::size_t b = 0; b < 5; ++b) {
            f.data[7 * b + 6] = static_cast<std::uint8_t>((f.data[7 * b + 6] & 0x0F) | 0x30);
          }
        }
        if (f.len > 0) f.data[f.len - 1u] = tp::frame_crc(f);
        const tp::Status s = tp::decode(f, tp::IdLayout{}, d);
        const bool doc = documented(id, f.fd, f.len);
        if (doc) {
          EXPECT_EQ(s, tp::Status::kOk) << std::hex << id << " len " << int(f.len);
          ++accepted;
          if (f.fd) ++accepted_fd;
          EXPECT_EQ(d.node_id, (id >> 5) & 0x3F);
          EXPECT_EQ(static_cast<unsigned>(d.message), id & 0x1F);
        } else {
          EXPECT_NE(s, tp::Status::kOk) << std::hex << id << " len " << int(f.len);
        }
        // The reassembler and the command receiver take any frame without misbehaving.
        tp::Cycle c;
        (void)reasm.feed(f, c);
        (void)rx.receive(f);
      }
    }
  }
  // 63 nodes x 11 eight-byte messages, classic and FD-with-len-8, plus 63 CycleFd frames.
  EXPECT_EQ(accepted, 63u * 11u * 2u + 63u);
  EXPECT_EQ(accepted_fd, 63u * 11u + 63u);
  EXPECT_GT(crc_rejected, 1000u);
  // Identifier 0x000 (NMT) is never ours.
  tp::CanFrame nmt;
  nmt.len = 8;
  tp::Decoded d;
  EXPECT_EQ(tp::decode(nmt, tp::IdLayout{}, d), tp::Status::kUnknownId);
  // The reassembler of node 1 accepted exactly node 1's valid cycle frames: 0x021..0x025 as
  // classic and as FD-with-len-8, and 0x026 as FD len 64; every other length of those six ids
  // (9 classic + 16 FD lengths each, minus the valid ones) was a length error.
  EXPECT_EQ(reasm.stats().frames, 5u * 2u + 1u);
  EXPECT_EQ(reasm.stats().length_errors, 5u * (25u - 2u) + (25u - 1u));
  EXPECT_EQ(reasm.stats().crc_errors, 0u);
  EXPECT_GT(rx.stats().other_node, 0u);
  EXPECT_GT(rx.stats().rejected(), 0u);
}

TEST(Spam, ExtendedIdentifiers) {
  std::mt19937 rng(99);
  tp::IdLayout ext;
  ext.mode = tp::IdMode::kExtended;
  std::size_t accepted = 0;
  // The whole tacse3 window under the base, plus random 29-bit ids outside it.
  for (std::uint32_t low = 0; low <= 0x7FF; ++low) {
    tp::CanFrame f;
    f.extended = true;
    f.id = tp::kDefaultExtendedBase | low;
    f.len = 8;
    for (std::size_t i = 0; i < 8; ++i) f.data[i] = static_cast<std::uint8_t>(rng());
    f.data[7] = tp::frame_crc(f);
    tp::Decoded d;
    const bool doc = documented(low, false, 8);
    EXPECT_EQ(tp::decode(f, ext, d) == tp::Status::kOk, doc) << std::hex << f.id;
    if (doc) ++accepted;
    // The same low bits as an 11-bit frame are not ours under the extended layout.
    tp::CanFrame s = f;
    s.extended = false;
    s.id = low;
    s.data[7] = tp::frame_crc(s);
    EXPECT_EQ(tp::decode(s, ext, d), tp::Status::kUnknownId);
  }
  EXPECT_EQ(accepted, 63u * 11u);
  for (int i = 0; i < 20000; ++i) {
    tp::CanFrame f;
    f.extended = true;
    f.id = rng() & tp::kExtendedIdMask;
    if ((f.id & ~tp::kStandardIdMask) == tp::kDefaultExtendedBase) continue;
    f.len = 8;
    f.data[7] = tp::frame_crc(f);
    tp::Decoded d;
    EXPECT_EQ(tp::decode(f, ext, d), tp::Status::kUnknownId);
  }
}

// Flipping any single payload bit or identifier bit of a valid frame is caught.
TEST(Spam, SingleBitErrorsAreCaught) {
  tp::Cycle c;
  c.timestamp_us = 987654321;
  c.angular = {0.1, 0.2, 0.3};
  tp::CycleFrames frames;
  ASSERT_EQ(tp::encode_cycle(c, 9, tp::TxConfig{}, frames), tp::Status::kOk);
  for (std::size_t k = 0; k < frames.count; ++k) {
    for (unsigned bit = 0; bit < 64; ++bit) {
      tp::CanFrame f = frames.frames[k];
      f.data[bit / 8] = static_cast<std::uint8_t>(f.data[bit / 8] ^ (1u << (bit % 8)));
      tp::Decoded d;
      EXPECT_EQ(tp::decode(f, tp::IdLayout{}, d), tp::Status::kBadCrc);
    }
    for (unsigned bit = 0; bit < 11; ++bit) {
      tp::CanFrame f = frames.frames[k];
      f.id ^= 1u << bit;
      tp::Decoded d;
      EXPECT_NE(tp::decode(f, tp::IdLayout{}, d), tp::Status::kOk) << "id bit " << bit;
    }
  }
}
