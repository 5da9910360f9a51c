// SPDX-License-Identifier: Apache-2.0
// tacse3 recording: 8-bit grey/RGB PNG encode and decode through libspng, with strict checks.
#include <spng.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "tacse3/recording/recording.hpp"

namespace tacse3::recording {
namespace {

struct FileCloser {
  void operator()(std::FILE* f) const noexcept {
    if (f) std::fclose(f);
  }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

struct CtxFree {
  void operator()(spng_ctx* c) const noexcept { spng_ctx_free(c); }
};
using CtxPtr = std::unique_ptr<spng_ctx, CtxFree>;

std::uint32_t be32(const unsigned char* p) {
  return (static_cast<std::uint32_t>(p[0]) << 24) | (static_cast<std::uint32_t>(p[1]) << 16) |
         (static_cast<std::uint32_t>(p[2]) << 8) | static_cast<std::uint32_t>(p[3]);
}

std::string name(const std::filesystem::path& p) {
  return p.string();
}

Status check_format(const std::filesystem::path& file, const PngHeader& h) {
  if (h.bit_depth != 8 || (h.colour_type != 0 && h.colour_type != 2)) {
    return Status::error(name(file) + ": PNG must be 8-bit RGB or 8-bit grey, got bit depth " +
                         std::to_string(h.bit_depth) + ", colour type " +
                         std::to_string(h.colour_type) +
                         (h.colour_type == 3   ? " (palette)"
                          : h.colour_type == 4 ? " (grey+alpha)"
                          : h.colour_type == 6 ? " (RGBA)"
                                               : ""));
  }
  return {};
}

}  // namespace

Status read_png_header(const std::filesystem::path& file, PngHeader* out) {
  FilePtr f(std::fopen(file.c_str(), "rb"));
  if (!f) return Status::error(name(file) + ": cannot open: " + std::strerror(errno));
  unsigned char b[33];
  if (std::fread(b, 1, sizeof b, f.get()) != sizeof b) {
    return Status::error(name(file) + ": not a PNG file (too short)");
  }
  static constexpr unsigned char kSig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (std::memcmp(b, kSig, 8) != 0)
    return Status::error(name(file) + ": not a PNG file (bad signature)");
  if (be32(b + 8) != 13 || std::memcmp(b + 12, "IHDR", 4) != 0) {
    return Status::error(name(file) + ": corrupt PNG (first chunk is not IHDR)");
  }
  out->width = static_cast<int>(be32(b + 16));
  out->height = static_cast<int>(be32(b + 20));
  out->bit_depth = b[24];
  out->colour_type = b[25];
  return {};
}

Status read_png(const std::filesystem::path& file, Image* out) {
  FilePtr f(std::fopen(file.c_str(), "rb"));
  if (!f) return Status::error(name(file) + ": cannot open: " + std::strerror(errno));
  CtxPtr ctx(spng_ctx_new(0));
  if (!ctx) return Status::error(name(file) + ": out of memory for the PNG decoder");
  spng_set_crc_action(ctx.get(), SPNG_CRC_ERROR, SPNG_CRC_ERROR);
  // A header may claim any size up to 2^31 per side; the decoded image is allocated from it, so
  // the reader bounds it first (a 29-byte file claimed 30720x65280, 6 GB, to the fuzzer).
  spng_set_image_limits(ctx.get(), kMaxPngSide, kMaxPngSide);
  spng_set_png_file(ctx.get(), f.get());
  spng_ihdr ihdr{};
  if (int e = spng_get_ihdr(ctx.get(), &ihdr); e != 0) {
    if (e == SPNG_EUSER_WIDTH || e == SPNG_EUSER_HEIGHT) {
      return Status::error(name(file) + ": PNG is larger than " + std::to_string(kMaxPngSide) +
                           " pixels on a side, the reader's limit");
    }
    return Status::error(name(file) + ": bad PNG header: " + spng_strerror(e));
  }
  PngHeader h{static_cast<int>(ihdr.width), static_cast<int>(ihdr.height), ihdr.bit_depth,
              ihdr.color_type};
  if (Status s = check_format(file, h); !s) return s;
  const int fmt = ihdr.color_type == SPNG_COLOR_TYPE_GRAYSCALE ? SPNG_FMT_G8 : SPNG_FMT_RGB8;
  std::size_t len = 0;
  if (int e = spng_decoded_image_size(ctx.get(), fmt, &len); e != 0) {
    return Status::error(name(file) + ": cannot size the PNG image: " + spng_strerror(e));
  }
  out->width = h.width;
  out->height = h.height;
  out->channels = fmt == SPNG_FMT_G8 ? 1 : 3;
  out->pixels.resize(len);
  if (int e = spng_decode_image(ctx.get(), out->pixels.data(), len, fmt, 0); e != 0) {
    return Status::error(name(file) + ": corrupt PNG data: " + spng_strerror(e));
  }
  return {};
}

Status write_png(const std::filesystem::path& file, const ImageView& im, int level) {
  if (!im.data || im.width <= 0 || im.height <= 0 || (im.channels != 1 && im.channels != 3)) {
    return Status::error(name(file) + ": invalid image (size or channel count)");
  }
  FilePtr f(std::fopen(file.c_str(), "wb"));
  if (!f) return Status::error(name(file) + ": cannot create: " + std::strerror(errno));
  CtxPtr ctx(spng_ctx_new(SPNG_CTX_ENCODER));
  if (!ctx) return Status::error(name(file) + ": out of memory for the PNG encoder");
  spng_set_png_file(ctx.get(), f.get());
  spng_set_option(ctx.get(), SPNG_IMG_COMPRESSION_LEVEL, level);
  if (level == 1) {
    // Sensor noise leaves deflate few string matches: Huffman-only coding of SUB-filtered rows
    // is about twice as fast as zlib level 1 and compresses noisy frames slightly better.
    constexpr int kZHuffmanOnly = 2;  // Z_HUFFMAN_ONLY in zlib.h
    spng_set_option(ctx.get(), SPNG_IMG_COMPRESSION_STRATEGY, kZHuffmanOnly);
    spng_set_option(ctx.get(), SPNG_FILTER_CHOICE, SPNG_FILTER_CHOICE_SUB);
  } else if (level == 0) {
    spng_set_option(ctx.get(), SPNG_FILTER_CHOICE, SPNG_FILTER_CHOICE_NONE);
  }
  spng_ihdr ihdr{};
  ihdr.width = static_cast<std::uint32_t>(im.width);
  ihdr.height = static_cast<std::uint32_t>(im.height);
  ihdr.bit_depth = 8;
  ihdr.color_type = im.channels == 1 ? SPNG_COLOR_TYPE_GRAYSCALE : SPNG_COLOR_TYPE_TRUECOLOR;
  spng_set_ihdr(ctx.get(), &ihdr);
  if (int e = spng_encode_image(ctx.get(), im.data, im.size(), SPNG_FMT_PNG, SPNG_ENCODE_FINALIZE);
      e != 0) {
    // A write error (ENOSPC) surfaces as libspng's "stream error": name the cause instead.
    const int write_errno = errno;
    if (std::ferror(f.get()) != 0)
      return Status::error(name(file) + ": write failed: " + std::strerror(write_errno));
    return Status::error(name(file) + ": PNG encoding failed: " + spng_strerror(e));
  }
  FILE* raw = f.release();
  if (std::fclose(raw) != 0) {
    return Status::error(name(file) + ": write failed: " + std::strerror(errno));
  }
  return {};
}

}  // namespace tacse3::recording
