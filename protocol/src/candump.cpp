// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: candump -L log line parser and formatter (no allocation, no locale).
#include "tacse3/protocol/candump.hpp"

namespace tacse3::protocol {
namespace {

constexpr std::uint32_t kCanErrFlag = 0x20000000u;

int hex_value(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

bool is_space(char c) noexcept {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

struct Cursor {
  std::string_view s;
  std::size_t i = 0;
  bool done() const noexcept { return i >= s.size(); }
  char peek() const noexcept { return done() ? '\0' : s[i]; }
  void skip_spaces() noexcept {
    while (!done() && is_space(s[i])) ++i;
  }
};

bool parse_decimal(Cursor& c, std::uint64_t& v, std::size_t& digits) noexcept {
  v = 0;
  digits = 0;
  while (!c.done() && c.peek() >= '0' && c.peek() <= '9') {
    if (v > (~std::uint64_t{0} - 9) / 10) return false;
    v = v * 10 + static_cast<std::uint64_t>(c.peek() - '0');
    ++c.i;
    ++digits;
  }
  return digits > 0;
}

char hex_digit(unsigned v) noexcept {
  return "0123456789ABCDEF"[v & 0x0Fu];
}

}  // namespace

Status parse_candump_line(std::string_view line, LogRecord& out) noexcept {
  out = LogRecord{};
  Cursor c{line};
  c.skip_spaces();
  // (seconds.microseconds)
  if (c.peek() != '(') return Status::kParseError;
  ++c.i;
  std::uint64_t sec = 0, frac = 0;
  std::size_t sd = 0, fd = 0;
  if (!parse_decimal(c, sec, sd)) return Status::kParseError;
  if (c.peek() != '.') return Status::kParseError;
  ++c.i;
  if (!parse_decimal(c, frac, fd) || fd > 9) return Status::kParseError;
  while (fd > 6) {
    frac /= 10;
    --fd;
  }
  while (fd < 6) {
    frac *= 10;
    ++fd;
  }
  if (c.peek() != ')') return Status::kParseError;
  ++c.i;
  if (sec > (~std::uint64_t{0}) / 1000000u - 1u) return Status::kParseError;
  out.time_us = sec * 1000000u + frac;
  // interface
  if (!is_space(c.peek())) return Status::kParseError;
  c.skip_spaces();
  std::size_t n = 0;
  while (!c.done() && !is_space(c.peek())) {
    // Interface names are printable ASCII (no NUL or control characters).
    if (c.peek() < '!' || c.peek() > '~') return Status::kParseError;
    if (n >= out.iface.size() - 1) return Status::kParseError;
    out.iface[n++] = c.peek();
    ++c.i;
  }
  if (n == 0) return Status::kParseError;
  c.skip_spaces();
  // identifier
  std::uint32_t id = 0;
  std::size_t id_digits = 0;
  while (!c.done() && c.peek() != '#') {
    const int h = hex_value(c.peek());
    if (h < 0 || id_digits >= 8) return Status::kParseError;
    id = (id << 4) | static_cast<std::uint32_t>(h);
    ++id_digits;
    ++c.i;
  }
  if (c.peek() != '#') return Status::kParseError;
  ++c.i;
  CanFrame& f = out.frame;
  if (id_digits == 3) {
    if (id > kStandardIdMask) return Status::kParseError;
    f.extended = false;
    f.id = id;
  } else if (id_digits == 8) {
    if ((id & kCanErrFlag) != 0) {
      out.error_frame = true;
      id &= kExtendedIdMask;
    } else if (id > kExtendedIdMask) {
      return Status::kParseError;
    }
    f.extended = true;
    f.id = id;
  } else {
    return Status::kParseError;
  }
  // payload
  if (c.peek() == '#') {
    ++c.i;
    const int flags = hex_value(c.peek());
    if (flags < 0) return Status::kParseError;
    ++c.i;
    f.fd = true;
    f.brs = (flags & 0x1) != 0;
  } else if (c.peek() == 'R' || c.peek() == 'r') {
    ++c.i;
    out.rtr = true;
    if (!c.done() && !is_space(c.peek())) {
      const int len = hex_value(c.peek());
      if (len < 0 || len > 8) return Status::kParseError;
      f.len = static_cast<std::uint8_t>(len);
      ++c.i;
    }
  }
  if (!out.rtr) {
    std::size_t len = 0;
    while (!c.done() && hex_value(c.peek()) >= 0) {
      const int hi = hex_value(c.peek());
      ++c.i;
      const int lo = hex_value(c.peek());
      if (lo < 0) return Status::kParseError;
      ++c.i;
      if (len >= (f.fd ? kFdMaxLen : kClassicMaxLen)) return Status::kParseError;
      f.data[len++] = static_cast<std::uint8_t>((hi << 4) | lo);
    }
    if (!is_valid_length(f.fd, len)) return Status::kParseError;
    f.len = static_cast<std::uint8_t>(len);
    if (!f.fd && c.peek() == '_') {  // len8_dlc suffix of a classic 8-byte frame
      ++c.i;
      if (len != 8 || hex_value(c.peek()) < 9) return Status::kParseError;
      ++c.i;
    }
  }
  // optional direction marker written by some tools (" R" / " T"), nothing else
  c.skip_spaces();
  if (c.peek() == 'R' || c.peek() == 'T') {
    ++c.i;
    c.skip_spaces();
  }
  if (!c.done()) return Status::kParseError;
  return Status::kOk;
}

std::size_t format_candump_line(const LogRecord& r, char* buf, std::size_t cap) noexcept {
  if (buf == nullptr || cap == 0) return 0;
  const CanFrame& f = r.frame;
  if (!is_valid_length(f.fd, f.len)) return 0;
  std::size_t n = 0;
  bool overflow = false;
  auto put = [&](char ch) {
    if (n + 1 < cap) {
      buf[n++] = ch;
    } else {
      overflow = true;
    }
  };
  auto put_dec = [&](std::uint64_t v, int width) {
    char tmp[24];
    int k = 0;
    do {
      tmp[k++] = static_cast<char>('0' + v % 10);
      v /= 10;
    } while (v != 0 && k < 24);
    for (int pad = k; pad < width; ++pad) put('0');
    while (k > 0) put(tmp[--k]);
  };
  put('(');
  put_dec(r.time_us / 1000000u, 10);
  put('.');
  put_dec(r.time_us % 1000000u, 6);
  put(')');
  put(' ');
  std::size_t iface_len = 0;
  for (char ch : r.iface) {
    if (ch == '\0') break;
    if (is_space(ch)) return 0;
    put(ch);
    ++iface_len;
  }
  if (iface_len == 0) return 0;
  put(' ');
  if (f.extended || r.error_frame) {
    const std::uint32_t id = (f.id & kExtendedIdMask) | (r.error_frame ? kCanErrFlag : 0u);
    for (int s = 28; s >= 0; s -= 4) put(hex_digit(id >> s));
  } else {
    for (int s = 8; s >= 0; s -= 4) put(hex_digit((f.id & kStandardIdMask) >> s));
  }
  put('#');
  if (f.fd) {
    put('#');
    put(hex_digit(f.brs ? 1u : 0u));
  }
  if (r.rtr && !f.fd) {
    put('R');
    if (f.len > 0 && f.len <= kClassicMaxLen) put(hex_digit(f.len));
  } else {
    for (std::size_t i = 0; i < f.len; ++i) {
      put(hex_digit(f.data[i] >> 4));
      put(hex_digit(f.data[i]));
    }
  }
  if (overflow) return 0;
  buf[n] = '\0';
  return n;
}

}  // namespace tacse3::protocol
