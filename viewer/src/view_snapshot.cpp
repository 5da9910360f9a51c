// SPDX-License-Identifier: Apache-2.0
// tacse3 viewer: a view's per-pad copy of the pipeline's last fields.
#include "tacse3/viewer/view_snapshot.hpp"

#include <algorithm>

namespace tacse3::viewer {

namespace {

constexpr float kQ16 = 1.0f / static_cast<float>(1 << dsp::kFieldFrac);

}  // namespace

void fill_view_pad(const dsp::SensorPipeline& p, const dsp::SensorResult& r, bool present,
                   ViewPad* out) noexcept {
  const dsp::SensorFields& f = p.fields();
  out->present = present;
  out->contact = present && f.contact.count > 0;
  out->slipping = present && r.slipping;
  out->contact_area_m2 = present ? contact_area_m2(p) : 0.0;
  out->tracked_fraction = present ? static_cast<double>(r.tracked_points) / dsp::kGridCount : 0.0;
  fill_view_pad_fields(f, out);
}

void fill_view_pad_fields(const dsp::SensorFields& f, ViewPad* out) noexcept {
  // Working luma is U8.2 (luma * 4).
  for (std::size_t i = 0; i < out->luma.size(); ++i)
    out->luma[i] = static_cast<std::uint8_t>(std::min<int>(f.work.px[i] >> 2, 255));
  for (std::size_t i = 0; i < out->mask.size(); ++i) {
    out->mask[i] = f.contact.mask.v[i];
    out->shear_x[i] = static_cast<float>(f.shear.x.v[i]) * kQ16;
    out->shear_y[i] = static_cast<float>(f.shear.y.v[i]) * kQ16;
    out->fz[i] = static_cast<float>(f.fz.v[i]) * kQ16;
  }
}

double contact_area_m2(const dsp::SensorPipeline& p) noexcept {
  return contact_area_m2(p.calibration(), p.fields().contact.count);
}

double contact_area_m2(const dsp::Calibration& cal, int contact_cells) noexcept {
  const double cell_m =
      cal.pixel_pitch_m * (static_cast<double>(dsp::kSensorWidth) / dsp::kGridWidth);
  return static_cast<double>(contact_cells) * cell_m * cell_m * cal.pixel_aspect_y;
}

}  // namespace tacse3::viewer
