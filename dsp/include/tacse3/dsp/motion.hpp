// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: per-sensor motion: contact-centroid translation, velocity proxy, int64 moments, ω.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "tacse3/dsp/calibration.hpp"
#include "tacse3/dsp/contact.hpp"
#include "tacse3/dsp/load_release.hpp"
#include "tacse3/dsp/slip_detector.hpp"
#include "tacse3/dsp/solve3.hpp"
#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {

// Velocity-proxy samples entering the moments are clamped to ±kMaxProxyQ16 (Q16 shear units,
// ±128 working px) so that the moment sums below cannot overflow int64.
inline constexpr std::int32_t kMaxProxyQ16 = (std::int32_t{1} << 23) - 1;

// Per-sensor sufficient statistics of the shear-only least squares (Eq. twist_ls restricted to
// ω, paper Sec. IV-C/D), accumulated over Ω in the SENSOR frame.
// Units: q in nm (contact.hpp), ṽ in Q16 proxy units (shear, or shear increment, per point);
// ṽ_z = 0 (shear-only). Scaling and overflow: N ≤ 1200 < 2^11, |q_x|,|q_y| < 2^25, 0 ≤ q_z < 2^24,
// |ṽ| < 2^23, so Σ q qᵀ < 2^61, Σ q ṽ < 2^59 and Σ |ṽ|² < 2^58: exact in int64, no saturation
// needed.
struct ContactMoments {
  std::int64_t n = 0;
  std::int64_t sx = 0, sy = 0, sz = 0;                                // Σ q
  std::int64_t sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;  // Σ q qᵀ
  std::int64_t svx = 0, svy = 0;                                      // Σ ṽ
  std::int64_t sx_vy = 0, sy_vx = 0, sz_vx = 0, sz_vy = 0;  // Σ q_a ṽ_b used by Σ q×ṽ
  std::int64_t svv = 0;  // Σ |ṽ|² (the fit residual, fit_quality() in fusion.hpp)
};

// The same sums in double and SI units (m, m/s), in some frame F, plus the unit normal n_F of the
// sensor whose points they are (the direction whose velocity equation is dropped).
struct MomentSums {
  double n = 0.0;
  Eigen::Vector3d s1 = Eigen::Vector3d::Zero();    // Σ q
  Eigen::Matrix3d s2 = Eigen::Matrix3d::Zero();    // Σ q qᵀ
  Eigen::Vector3d sv = Eigen::Vector3d::Zero();    // Σ ṽ
  Eigen::Vector3d sqxv = Eigen::Vector3d::Zero();  // Σ q × ṽ
  double svv = 0.0;                                // Σ |ṽ|²
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};

// Integer moments → SI, sensor frame (normal = +z_S). proxy_scale: (m/s) per Q16 proxy LSB.
MomentSums to_metric(const ContactMoments& m, double proxy_scale) noexcept;

// Moments of the transformed points q' = R q + p and vectors ṽ' = R ṽ (R orthonormal):
//   Σq' = R Σq + N p,  Σq'q'ᵀ = R Σqqᵀ Rᵀ + (R Σq) pᵀ + p (R Σq)ᵀ + N p pᵀ,
//   Σṽ' = R Σṽ,  Σ q'×ṽ' = R Σ q×ṽ + p × R Σṽ,  Σ|ṽ'|² = Σ|ṽ|²,  n' = R n.
MomentSums rigid_transform(const MomentSums& m, const Eigen::Matrix3d& R,
                           const Eigen::Vector3d& p) noexcept;

// Adds one sensor's shear-only normal equations to (AtA, Atb). Per point the residual is the
// tangential part P(ω × q − ṽ), P = I − n nᵀ; in the sensor frame its rows are exactly the first
// two rows of the paper's A_i restricted to ω, [0, z, −y] and [−z, 0, x]. Summed:
//   AᵀA = tr(Σqqᵀ) I − Σqqᵀ − [n]× Σqqᵀ [n]×ᵀ,   Aᵀb = Σ q × ṽ   (ṽ ⟂ n).
void add_normal_equations(const MomentSums& m, Eigen::Matrix3d& AtA, Eigen::Vector3d& Atb) noexcept;

// Planar rigid-body content X = [L·θ, t_x, t_y] (m) of the proxy in `m` read with `scale`
// (metres per Q16 LSB): t the mean, θ = Σ (r × ṽ)_z / Σ |r|² the rotation about the pad normal
// through the contact centroid (r = q − c in the pad plane), L = √(Σ |r|² / N) the rms lever, so
// L·θ = Σ (r × ṽ)_z / √(N Σ |r|²). Used by the kAuto stick/slip detector; zero without points.
Eigen::Vector3d planar_content(const ContactMoments& m, double scale) noexcept;

enum class TranslationSource : std::uint8_t {
  kNone = 0,      // no translation this frame (no contact now or before, or disjoint masks)
  kCentroid = 1,  // displacement of the height-weighted mask centroid (paper Sec. IV-D, weighted)
  kCommonPoints = 2,  // sticking, or mask changed beyond the gate: mean displacement of the
                      // material points in both masks
};

// The velocity proxy's region (docs/dsp/motion.md, drag region). A drag (the in-plane part of a
// slide: a rotation about an in-plane axis or a translation) moves the gel over the patch rigidly
// and the gel around it less, so the density 𝒢 reads compression ahead of the patch and expansion
// behind it, and Ω leaves the patch's leading part for the stretched gel behind it, whose shear
// has decayed: the reading would depend on the speed of the slide. Over the patch anchored before
// the load, the shear is the patch's own. A torsion has no divergence and leaves Ω in place,
// while an elongated patch turns away from its anchor; a translation carries the patch off its
// anchor. So Ω ∩ anchor is read only while the shear's uniform part exceeds
// kVelocityAnchorDragRatio times its torsion (the torsion as the displacement on the rms lever,
// planar_content over Ω) and Ω ∩ anchor holds at least kVelocityAnchorMinOverlap of the smaller
// of Ω and the anchor (a tilting flat face keeps a strip of its anchored face; a translation
// leaves both); otherwise all of Ω (also on a frame without shear, and before the first anchor).
inline constexpr double kVelocityAnchorDragRatio = 1.0;
inline constexpr double kVelocityAnchorMinOverlap = 0.5;
// The rule above, shared by MotionEstimator and the double reference: true when the velocity
// proxy reads Ω ∩ anchor. shear_content: planar_content of the shear over Ω (any one scale);
// held: |Ω ∩ anchor|; anchor_cells: |anchor| (0 without one); contact_cells: |Ω|.
bool velocity_reads_anchor(const Eigen::Vector3d& shear_content, std::int64_t held,
                           std::int64_t anchor_cells, std::int64_t contact_cells) noexcept;

// Per-sensor, per-frame result (sensor frame S).
struct SensorMotion {
  bool contact = false;
  int points = 0;
  // This frame's proxy moments, sensor frame: over Ω or Ω ∩ anchor (velocity proxy, see
  // velocity_anchored) or over Ω_t ∩ Ω_{t−1} ∩ anchor (displacement proxy, the cells with an
  // increment).
  ContactMoments moments;
  double proxy_scale = 0.0;  // (m/s) per Q16 LSB of the proxy in `moments`
  bool proxy_valid = false;  // false on the first displacement-mode frame after reset
  Eigen::Vector3d centroid_m = Eigen::Vector3d::Zero();  // 3D centroid of q over Ω (m)
  // The contact point whose velocity `translation` is (m): the height-weighted centroid
  // Σ z q / Σ z for the sliding rule (kCentroid; centroid_m when this or the previous frame has
  // Σ z = 0), centroid_m otherwise. The fusion refers the
  // translation to G's origin from here (t = v − ω × point).
  Eigen::Vector3d translation_point_m = Eigen::Vector3d::Zero();
  // Contact-centroid velocity (m/s), t_z = 0, translation_scale applied.
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  bool translation_valid = false;
  TranslationSource translation_source = TranslationSource::kNone;
  double mask_change = 0.0;  // 1 − Jaccard(Ω_t, Ω_{t−1}); 1 when either is empty
  // Own-frame shear-only rotation (rad/s), rotation_scale applied; what the paper fuses.
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();
  Solve3Result solve;
  bool rotation_valid = false;  // contact && proxy_valid && solve.valid
  Eigen::Vector3d rotation_scale = Eigen::Vector3d::Ones();  // copied for the joint fusion
  // --- stick/slip detector (kAuto only; false/0 in the fixed modes).
  bool slipping = false;         // the velocity proxy was used this frame
  bool slip_onset = false;       // the detector switched stick → slip this frame
  bool stick_confirmed = false;  // the shear was held at rest long enough: a stuck contact
  double slip_relax_rate = 0.0;  // ρ (1/s), relative decay rate of the shear's rigid content
  double shear_shift_m = 0.0;    // |X| (m), rigid content of the shear read as a displacement
  double shear_rate_m_s = 0.0;   // |dX|/Δt (m/s), rigid content of this frame's increment
  // ρ_L (1/s), relative rate at which the normal load Σ z over Ω falls (smoothed like X; < 0
  // while it rises; every mode). kAuto counts only shear relaxation beyond it towards an onset.
  double load_drop_rate = 0.0;
  // Sticking (kDisplacement, or kAuto not slipping) with ρ_L > release_load_rate: the contact is
  // being let go, and this frame's chosen reading is dropped (proxy_valid, translation_valid
  // false, ω = 0). The velocity reading beside it (kAuto) is kept: it only counts if a slide is
  // detected afterwards (the payback's deficit), and a releasing frame may be a slide's.
  bool releasing = false;
  // The displacement proxy's patch anchor was set to this frame's Ω (every mode): the contact's
  // first frame, a tangentially unloaded shear (|X| ≤ slip_min_shift_m, X over Ω unsmoothed),
  // or the frame a slide ended. Increments are read over Ω_t ∩ Ω_{t−1} ∩ anchor
  // (docs/dsp/motion.md, patch anchor).
  bool anchor_set = false;
  // The velocity proxy was read over Ω ∩ anchor instead of all of Ω (every mode;
  // docs/dsp/motion.md, drag region): the shear over Ω is a drag (|t| > |θ|·L in
  // planar_content, kVelocityAnchorDragRatio) and Ω and the anchor share at least
  // kVelocityAnchorMinOverlap of the smaller one's cells.
  bool velocity_anchored = false;
  // The cells the velocity proxy read: |Ω ∩ anchor| or |Ω| (every mode), and |Ω ∩ anchor|
  // (0 without an anchor), what the overlap test compares.
  int velocity_points = 0;
  int anchor_overlap_points = 0;
  // --- the same frame as kVelocity would have read it: the velocity proxy's moments and ω, and
  // the sliding translation rule. Differs from the reading above only while kAuto sticks
  // (velocity_differs); otherwise a copy of it. Its region follows this estimator's anchor,
  // which kAuto also sets where a slide ends (kVelocity never does). The dual pipeline fuses
  // both readings and pays the difference back at a slip onset (SlipPayback).
  bool velocity_differs = false;
  ContactMoments velocity_moments;
  double velocity_proxy_scale = 0.0;
  Eigen::Vector3d velocity_rotation_scale = Eigen::Vector3d::Ones();
  Eigen::Vector3d velocity_omega = Eigen::Vector3d::Zero();
  Solve3Result velocity_solve;
  Eigen::Vector3d velocity_translation = Eigen::Vector3d::Zero();
  bool velocity_translation_valid = false;
  Eigen::Vector3d velocity_translation_point_m = Eigen::Vector3d::Zero();
};

// `m` as kVelocity would have read the frame: its velocity_* fields in place of the chosen
// reading (proxy defined with contact) while velocity_differs; otherwise `m` itself. Used to fuse
// the velocity reading beside the chosen one.
SensorMotion velocity_reading(const SensorMotion& m) noexcept;

// Per-sensor motion stage. State: previous mask, positions, centroid sums, shear field and the
// detector's few scalars; no heap.
//  - Translation (paper Sec. IV-D "contact-centroid planar translation"): c_t = centroid of the
//    current positions over Ω_t, weighted by their height z (the indentation estimate, so the
//    rim cells that flicker in and out of Ω hardly move it; the plain mean if Σ z = 0 in this
//    or the previous frame); t = (c_t − c_{t−1}) / Δt, t_z = 0. Spike rules:
//      * onset (Ω_{t−1} empty) or loss (Ω_t empty): t = 0, translation_valid = false;
//      * Ω_t ∩ Ω_{t−1} empty (unrelated contacts, not a slide): t = 0, translation_valid = false;
//      * kDisplacement proxy, or kAuto while sticking: t is the mean displacement of the material
//        points present in both masks — exact kinematics, and blind to Ω creeping backwards
//        when a tangential load stretches the gel behind the patch (𝒢 reads that as expansion);
//      * if 1 − |Ω_t ∩ Ω_{t−1}| / |Ω_t ∪ Ω_{t−1}| > max_mask_change (off by default), cells
//        entering/leaving would move the centroid without any object motion, so t is the mean
//        displacement of the material points present in both masks (exact while the contact
//        sticks; zero in a slide, hence off by default);
//      * if the larger of |Ω_t|, |Ω_{t−1}| exceeds max_mask_area_ratio times the smaller (a
//        contact forming or vanishing: its centroid jumps with nothing moving, while a sliding
//        patch keeps its area), the same mean displacement of the common material points;
//      * otherwise the weighted centroid's displacement (also follows a sliding patch). With
//        kVelocity this includes a centroid shift from pressing harder on a tilted object, or
//        from pressure moving within the patch (rolling), which no rule here can tell from a
//        slide; kAuto reads those, while the contact sticks, from the material points.
//  - Velocity proxy ṽ: kVelocity ṽ = c_velocity · shear over Ω, or over
//    Ω ∩ anchor while the shear is a drag and Ω and the anchor share at least half the smaller
//    one's cells (above); kDisplacement
//    ṽ = c_displacement · (shear_t − shear_{t−1}) / Δt over Ω_t ∩ Ω_{t−1}, the previous shear
//    kept per sensor.
//  - Rotation: int64 moments over the proxy's cells, then in double the own-frame normal
//    equations and solve3 with λ = λ_rel tr/3 + N · lever_floor²; per-axis scales
//    rotation_scale (velocity proxy) or rotation_scale ⊙ displacement_rotation_ratio.
//  - Release (docs/dsp/motion.md): the normal load L = Σ z over Ω and its relative rate of fall
//    ρ_L, smoothed like X, in every mode. A sticking contact (kDisplacement, or kAuto not
//    slipping) with ρ_L > release_load_rate is being let go (the gel springs back): this frame's
//    chosen reading is dropped (`releasing`). kAuto's onset counts only ρ − max(0, ρ_L), and no
//    frame with ρ_L > release_load_rate.
//  - kAuto (per frame): both proxies' moments are summed in the same pass; the stick/slip
//    detector (Calibration, docs/dsp/motion.md) picks one. While sticking, the velocity proxy's
//    reading (its ω and the sliding translation rule) is reported beside the displacement
//    proxy's; the dual pipeline fuses both and SlipPayback pays back their fused difference at a
//    slip onset.
class MotionEstimator {
 public:
  MotionEstimator() noexcept;  // configured with Calibration{} defaults
  // kBadCalibration (previous configuration kept) if validate(cal) fails.
  Status configure(const Calibration& cal) noexcept;
  // Forget the previous frame and the patch anchor (call on tare, a degraded frame, a new
  // configuration).
  void reset() noexcept;
  // Forget the previous frame but keep the patch anchor (call after a gap in the stream or a
  // missed frame): a tangential load held across the gap has left the gel stretched, and the
  // Ω of the next frame would anchor the stretched extent (docs/dsp/motion.md). The next frame
  // without contact, or tangentially unloaded, replaces the anchor as usual. While sliding, the
  // anchor is dropped (the slide's end, which re-anchors, may fall in the gap).
  void restart() noexcept;

  // contact: this frame's ContactSet; shear: calibrated shear field (Q16 shear units);
  // dt_s: time since the previous frame, finite and in (0, 1] s.
  // Bad dt: returns kBadArgument, `out` = no contact / all invalid, state unchanged.
  Status update(const ContactSet& contact, const VectorField& shear, double dt_s,
                SensorMotion& out) noexcept;

 private:
  // update()'s steps, in order (dsp/src/motion.cpp).
  struct Pass {
    ContactMoments m;                   // Ω_t: points only
    ContactMoments shear;               // Ω_t with the shear (velocity proxy)
    ContactMoments increment;           // Ω_t ∩ Ω_{t−1} with the shear's increment
    ContactMoments anchored_increment;  // the same over the anchored patch
    ContactMoments held;                // Ω_t ∩ anchor with the shear
    std::int64_t common = 0, common_dx = 0, common_dy = 0;  // Ω_t ∩ Ω_{t−1}, summed steps (nm)
    std::int64_t anchored_common = 0, anchored_dx = 0, anchored_dy = 0;
  };
  struct SlideStep {
    Eigen::Vector2d disp = Eigen::Vector2d::Zero();  // m
    TranslationSource source = TranslationSource::kNone;
    Eigen::Vector3d point = Eigen::Vector3d::Zero();  // the point the step was read at
  };
  Pass gather(const ContactSet& contact, const VectorField& shear) const noexcept;
  bool decide_proxy(const Pass& p, const Eigen::Vector3d& shear_content, double dt_s,
                    bool* slide_ended, SensorMotion& out) noexcept;
  SlideStep slide_step(const Pass& p, double mask_change,
                       const Eigen::Vector3d& centroid) const noexcept;
  void translate(const Pass& p, bool sticking, double dt_s, SensorMotion& out) const noexcept;
  Eigen::Vector3d solve_rotation(const ContactMoments& sums, double scale,
                                 const Eigen::Vector3d& axis_scale,
                                 Solve3Result& result) const noexcept;
  void rotate(const ContactMoments& velocity, double velocity_scale, std::int64_t contact_cells,
              SensorMotion& out) const noexcept;
  void remember(const ContactSet& contact, const VectorField& shear, const ContactMoments& m,
                double shear_shift_m, bool slide_ended, SensorMotion& out) noexcept;

  VelocityProxy mode_ = VelocityProxy::kVelocity;
  double c_velocity_ = 0.0;
  double c_displacement_ = 0.0;
  double max_mask_change_ = 0.0;
  double max_mask_area_ratio_ = 1e4;
  Eigen::Vector3d rotation_scale_ = Eigen::Vector3d::Ones();
  Eigen::Vector3d displacement_rotation_scale_ = Eigen::Vector3d::Ones();  // ⊙ ratio
  Eigen::Vector3d translation_scale_ = Eigen::Vector3d::Ones();
  Solve3Options solve_options_;
  double lever_floor_m_ = 0.0;

  GridMask prev_mask_;
  GridArray<std::int32_t> prev_x_nm_;
  GridArray<std::int32_t> prev_y_nm_;
  std::int64_t prev_count_ = 0;
  std::int64_t prev_sx_ = 0;
  std::int64_t prev_sy_ = 0;
  std::int64_t prev_sz_ = 0;   // Σ z over Ω_{t−1} (weights of the sliding rule's centroid)
  std::int64_t prev_sxz_ = 0;  // Σ x z
  std::int64_t prev_syz_ = 0;  // Σ y z
  VectorField prev_shear_;
  bool have_prev_shear_ = false;
  // The contact patch as of the last frame its shear was tangentially unloaded (|X| ≤
  // slip_min_shift_m), or its first frame, or the frame a slide ended: the cells the displacement
  // proxy reads increments from. A tangential load stretches the gel behind the patch, which
  // 𝒢 reads as normal load, so Ω grows over gel that does not move with the object.
  GridMask anchor_mask_;
  bool have_anchor_ = false;
  std::int64_t anchor_count_ = 0;  // |anchor|

  // --- kAuto: the stick/slip detector; slip_min_shift_m is also the anchor's unloaded bar.
  SlipDetector detector_;
  double min_shift_m_ = 0.0;
  // Normal load (every mode): the release rule's load rate; L_{t−1} is prev_sz_.
  LoadRelease release_;
};

}  // namespace tacse3::dsp
