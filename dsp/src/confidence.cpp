// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: the confidence of the fused twist, one number in [0, 1] for a controller.
#include "tacse3/dsp/confidence.hpp"

#include <cmath>
#include <numbers>

namespace tacse3::dsp {
namespace {

double clamp01(double x) noexcept {
  return x > 0.0 ? (x < 1.0 ? x : 1.0) : 0.0;  // NaN → 0
}

// v² / (v² + e²): 1 for an error far below the scale v, ½ at e = v, → 0 above.
double below_scale(double error, double scale) noexcept {
  const double v2 = scale * scale;
  const double d = v2 + error * error;
  return d > 0.0 ? clamp01(v2 / d) : 0.0;
}

// The fraction of a disc of `cells` cells that lies at least `footprint` cells inside its rim.
double interior_fraction(int cells, double footprint) noexcept {
  if (cells <= 0) return 0.0;
  const double radius = std::sqrt(static_cast<double>(cells) / std::numbers::pi);
  const double inner = clamp01(1.0 - footprint / radius);
  return inner * inner;
}

}  // namespace

void TwistConfidence::configure(const ConfidenceConfig& config) noexcept {
  config_ = config;
  reset();
}

void TwistConfidence::reset() noexcept {
  catchup_left_ = 0;
  disagreement_ = 0.0;
  have_disagreement_ = false;
  terms_ = Terms{};
}

void TwistConfidence::smooth_disagreement(const FitQuality& q, double dt_s) noexcept {
  const double d = std::isfinite(q.disagreement_m_s) ? q.disagreement_m_s : 0.0;
  if (q.pads != 2 || !have_disagreement_) {
    // One pad has nothing to disagree with; a second pad's first frame starts the average.
    disagreement_ = q.pads == 2 ? d : 0.0;
    have_disagreement_ = q.pads == 2;
    return;
  }
  const double a =
      config_.smoothing_s > 0.0 && dt_s > 0.0 ? 1.0 - std::exp(-dt_s / config_.smoothing_s) : 1.0;
  disagreement_ += a * (d - disagreement_);
}

const TwistConfidence::Terms& TwistConfidence::update(const FitQuality& q, bool slipping,
                                                      bool onset, double dt_s) noexcept {
  Terms t;
  // The onset frame itself and the catch-up frames after it (the payback starts on the onset
  // frame, slip_payback.hpp).
  if (onset) catchup_left_ = config_.catchup_frames + 1;
  const bool catching_up = catchup_left_ > 0;
  if (catchup_left_ > 0) --catchup_left_;
  t.stick = slipping || catching_up ? 0.0 : 1.0;
  smooth_disagreement(q, dt_s);
  if (q.pads > 0) {
    t.observed = clamp01(q.rank / 3.0);
    t.conditioning = q.rcond_expected > 0.0 ? clamp01(q.rcond / q.rcond_expected) : 0.0;
    t.residual = below_scale(q.residual_speed_m_s, config_.rest_speed_m_s);
    t.agreement = below_scale(disagreement_, config_.rest_speed_m_s);
    t.area = interior_fraction(q.min_points, config_.footprint_cells);
    t.value = clamp01(t.observed * t.conditioning * t.residual * t.agreement * t.area * t.stick);
  }
  terms_ = t;
  return terms_;
}

}  // namespace tacse3::dsp
