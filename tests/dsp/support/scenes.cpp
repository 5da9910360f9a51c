// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: synthetic dual-pad grasp sequences (indentation bulge + rigid object motion).
#include "support/scenes.hpp"

#include <algorithm>
#include <cmath>

namespace tacse3::test {
namespace {

double smooth_step(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

}  // namespace

int scene_frames(const GraspScene& s) {
  return s.grasp_frames + s.motion_frames + s.hold_frames;
}

dsp::Pose scene_pose(const GraspScene& s, int frame) {
  const double progress = smooth_step(static_cast<double>(frame - s.grasp_frames) /
                                      static_cast<double>(s.motion_frames));
  return dsp::se3_exp(s.motion * progress);
}

std::vector<std::uint8_t> render_scene_frame(const GraspScene& s, const DotTexture& texture,
                                             int pad, int frame, const Photometric& ph) {
  const double indent = smooth_step(static_cast<double>(frame + 1) / s.grasp_frames);
  const dsp::Pose T = scene_pose(s, frame);
  const double P = s.pixel_pitch_m;
  const double z = pad == 0 ? 0.5 * s.separation_m : -0.5 * s.separation_m;
  const double ysign = pad == 0 ? 1.0 : -1.0;  // right pad: image y = −G y
  // The same physical patch: the right pad sees the left pad's centre mirrored in y.
  const double cx = s.centre_px[0];
  const double cy = pad == 0 ? s.centre_px[1] : 239.0 - s.centre_px[1];
  const double R = s.patch_radius_px;
  auto u = [&, indent](double i, double j) -> Vec2 {
    const double dx = i - cx, dy = j - cy;
    const double r = std::sqrt(dx * dx + dy * dy);
    // Radial push-out of the indentation, u_r = b (r/a) exp((1 − r²/a²)/2) with a = R/√2: the
    // gel expands (div u > 0) inside the patch, r < √2 a = R, and is compressed just outside.
    const double a = R / std::sqrt(2.0);
    const double b = s.bulge_px * indent * std::exp(0.5 * (1.0 - r * r / (a * a))) / a;
    // Rigid motion of the object's surface point seen at (i, j), projected on the pad plane.
    const Eigen::Vector3d q((i - 159.5) * P, ysign * (j - 119.5) * P, z);
    const Eigen::Vector3d x = dsp::transform_point(T, q);
    const double mi = x.x() / P + 159.5 - i;
    const double mj = ysign * x.y() / P + 119.5 - j;
    const double weight =
        r <= R ? 1.0 : std::exp(-(r - R) * (r - R) / (2.0 * s.spread_px * s.spread_px));
    return {b * dx + weight * mi, b * dy + weight * mj};
  };
  return render_frame(texture, Warp::displacement(u), dsp::PixelFormat::kRgb888, ph);
}

}  // namespace tacse3::test
