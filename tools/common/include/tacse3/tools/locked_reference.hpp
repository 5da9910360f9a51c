// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the fixed-point pipeline's per-frame decisions, for the decision-locked reference.
#pragma once

#include <array>

#include "tacse3/dsp/pipeline.hpp"
#include "tacse3/dsp_ref/pipeline_ref.hpp"

namespace tacse3::tools {

// Collects, after each fixed-point frame, the discrete decisions that dsp_ref::DualPipelineRef
// can follow (dsp_ref::FixedDecisions): each sensor's flow validity, keyframe switch (with its
// re-anchored and lost points), contact mask and stick/slip decision. The pointers refer to the
// pipeline's own fields and stay valid until its next frame. A sensor without a frame this time
// is not processed by the reference either (DualPipelineRef::process gets no view for it), so
// its stale fields are never read. docs/dsp/reference.md says what the decision-locked figure
// measures.
class DecisionFollower {
 public:
  // levels: which decisions to take; by default all of them.
  struct Levels {
    bool slip = true;
    bool flow = true;
    bool contact = true;
  };
  DecisionFollower() = default;
  explicit DecisionFollower(const Levels& levels) : levels_(levels) {}

  const std::array<dsp_ref::FixedDecisions, 2>& take(const dsp::DualPipeline& pipeline,
                                                     const dsp::DualResult& result) {
    for (std::size_t s = 0; s < 2; ++s) {
      const dsp::SensorResult& r = result.sensors[s];
      const dsp::SensorPipeline& sp = pipeline.sensor(static_cast<dsp::SensorSlot>(s));
      const dsp::SensorFields& f = sp.fields();
      slip_[s].slipping = r.motion.slipping;
      slip_[s].stick_confirmed = r.motion.stick_confirmed;
      slip_[s].slip_onset = r.motion.slip_onset;
      slip_[s].releasing = r.motion.releasing;
      slip_[s].has_anchor = true;
      slip_[s].anchor_set = r.motion.anchor_set;
      slip_[s].velocity_anchored = r.motion.velocity_anchored;
      dsp_ref::FixedDecisions& d = out_[s];
      d.slip = levels_.slip ? &slip_[s] : nullptr;
      d.flow.valid = levels_.flow ? &f.flow_valid : nullptr;
      d.flow.keyframe_switch = r.processed && r.keyframe_switched;
      d.flow.reanchored = levels_.flow ? &sp.flow().reanchored() : nullptr;
      d.flow.lost = levels_.flow ? &sp.flow().lost() : nullptr;
      d.flow.origin_x = levels_.flow ? &sp.flow().window_origin_x() : nullptr;
      d.flow.origin_y = levels_.flow ? &sp.flow().window_origin_y() : nullptr;
      d.contact = levels_.contact ? &f.contact.mask : nullptr;
    }
    return out_;
  }

 private:
  Levels levels_{};
  std::array<dsp_ref::SlipDecision, 2> slip_{};
  std::array<dsp_ref::FixedDecisions, 2> out_{};
};

}  // namespace tacse3::tools
