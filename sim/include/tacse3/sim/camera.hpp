// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: image formation: backward warp of the pattern, illumination, flicker and sensor
// noise.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "tacse3/sim/mjpeg.hpp"
#include "tacse3/sim/pad.hpp"
#include "tacse3/sim/pattern.hpp"
#include "tacse3/sim/types.hpp"

namespace tacse3::sim {

struct CameraSpec {
  double exposure = 0.9;                  // DN = 255 * exposure * reflectance * gains
  double vignetting_corner = 0.72;        // relative gain at the image corners (cos^4-like falloff)
  Eigen::Vector3d tint{1.0, 0.96, 0.90};  // LED colour (R, G, B gains)
  Eigen::Vector3d tint_gradient{0.06, 0.0, -0.06};  // gain change left -> right edge, per channel
  ShadingSpec shading;
  double flicker = 0.02;           // peak relative global gain change per frame (LED driver ripple)
  double flicker_hz = 7.0;         // slow beat component of the flicker
  double noise = 1.0;              // multiplier on shot + read noise; 0 = noiseless
  double electrons_per_dn = 20.0;  // conversion gain: shot-noise variance = DN / this
  double read_noise_dn = 1.0;
  // 0: frames as rendered. 1..100: each frame is JPEG-compressed at this quality and decoded, as
  // a UVC camera's MJPEG stream is (docs/sim-profiles.md).
  int mjpeg_quality = 0;
};

std::string validate(const CameraSpec& spec);

// One sensor's camera. build() allocates the per-pixel gain map, the interpolation tables and
// the noise tables; render() is allocation-free and reentrant per instance.
class Camera {
 public:
  void build(const RigSpec& rig, const CameraSpec& spec, std::uint64_t seed, Sensor sensor);

  // Global gain of the frame at t_ns (1 + flicker, deterministic from seed, sensor and t_ns).
  double flicker_gain(std::int64_t t_ns) const noexcept;

  // Renders width x height pixels, `channels` = 3 (RGB888) or 1 (GREY, BT.601 luma), tightly
  // packed into out. The gel material seen at pixel x came from x - total(x) (fields in mm,
  // bilinearly interpolated from the physics grid); its pattern colour is scaled by the
  // illumination, shading and flicker, then shot and read noise are added; an MJPEG camera
  // then compresses and decodes the frame. False if that round trip failed.
  bool render(const Pattern& pattern, const PadFields& fields, std::int64_t t_ns, std::uint8_t* out,
              int channels) noexcept;

  const RigSpec& rig() const noexcept { return rig_; }

 private:
  RigSpec rig_;
  CameraSpec spec_;
  std::uint64_t seed_ = 0;
  Sensor sensor_ = Sensor::kLeft;
  std::vector<float> gain_;  // per pixel R, G, B: 255 * exposure * vignetting * tint
  std::vector<int> xi0_, xi1_;
  std::vector<float> xw_;
  std::vector<float> row_x_, row_y_, row_s_;  // field rows interpolated along y (pixels)
  std::vector<float> line_;                   // one image row of linear values, w * 3
  std::vector<float> noise_line_;             // one image row of standard normal draws, w * 3
  std::vector<float> sigma_;                  // noise sigma per DN level
  std::vector<float> normal_;                 // standard normal quantiles (65536)
  MjpegCodec mjpeg_;
};

}  // namespace tacse3::sim
