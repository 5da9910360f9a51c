// SPDX-License-Identifier: Apache-2.0
// tacse3 bench: back-end stages (forces, contact, motion, solve, fusion, SE(3), moving average).
#include <benchmark/benchmark.h>

#include <memory>

#include "tacse3/dsp/calibration.hpp"
#include "tacse3/dsp/contact.hpp"
#include "tacse3/dsp/fixed.hpp"
#include "tacse3/dsp/force_map.hpp"
#include "tacse3/dsp/fusion.hpp"
#include "tacse3/dsp/motion.hpp"
#include "tacse3/dsp/moving_average.hpp"
#include "tacse3/dsp/se3.hpp"
#include "tacse3/dsp/solve3.hpp"
#include "tacse3/dsp_ref/motion_ref.hpp"

namespace {

using namespace tacse3::dsp;

constexpr double kDt = 1.0 / 120.0;
constexpr double kW = 30e-3;

// A realistic frame pair per pad: a 5 mm contact under a general rigid motion (≈ 300 of the
// 1200 grid points in contact), plus NHHD-like inputs for the force map.
struct Scene {
  std::unique_ptr<tacse3::dsp_ref::SyntheticSensorFrames> pad[2];
  ScalarField density;
  VectorField d, r, k;
  Scene() {
    const SensorExtrinsics e[2] = {left_pad_extrinsics(), right_pad_extrinsics()};
    for (int i = 0; i < 2; ++i) {
      tacse3::dsp_ref::RigidContactScene sc;
      sc.R_GS = e[i].R_GS;
      sc.p_GS = e[i].p_GS(kW);
      sc.contact_centre_G = Eigen::Vector3d(1e-3, -1e-3, sc.p_GS.z());
      sc.radius_m = 5e-3;
      sc.omega_G = Eigen::Vector3d(0.3, -0.2, 0.4);
      sc.t_G = Eigen::Vector3d(4e-3, -3e-3, 0.0);
      pad[i] = std::make_unique<tacse3::dsp_ref::SyntheticSensorFrames>(
          tacse3::dsp_ref::render_rigid_contact(Calibration{}, sc));
    }
    for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
      density.v[i] = -pad[0]->fz.v[i];  // f^z = −𝒢 with default gains
      d.x.v[i] = pad[0]->w_prev.x.v[i];
      d.y.v[i] = pad[0]->w_prev.y.v[i];
      r.x.v[i] = pad[0]->shear_now.x.v[i];
      r.y.v[i] = pad[0]->shear_now.y.v[i];
      k.x.v[i] = r.y.v[i];
      k.y.v[i] = -r.x.v[i];
    }
  }
};

const Scene& scene() {
  static const Scene s;
  return s;
}

void BM_ForceMap(benchmark::State& state) {
  const Scene& s = scene();
  Calibration cal;
  cal.normal_gain_divergence = state.range(0) != 0 ? 0.5 : 0.0;
  ForceMap fm;
  fm.configure(cal);
  auto fz = std::make_unique<ScalarField>();
  auto shear = std::make_unique<VectorField>();
  for (auto _ : state) {
    fm.compute(s.density, s.d, s.r, s.k, s.pad[0]->valid, *fz, *shear);
    benchmark::DoNotOptimize(fz->v.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_ForceMap)->Arg(0)->Arg(1)->ArgName("div");

void BM_ContactDetect(benchmark::State& state) {
  const Scene& s = scene();
  auto det = std::make_unique<ContactDetector>();
  auto cs = std::make_unique<ContactSet>();
  for (auto _ : state) {
    det->detect(s.pad[0]->fz, s.pad[0]->w_now, s.pad[0]->valid, *cs);
    benchmark::DoNotOptimize(cs->count);
  }
  state.counters["points"] = cs->count;
}
BENCHMARK(BM_ContactDetect);

void BM_MotionUpdate(benchmark::State& state) {
  const Scene& s = scene();
  Calibration cal;
  // 0 = velocity, 1 = displacement, 2 = auto (stick/slip detector, both readings and solves).
  cal.velocity_proxy = state.range(0) == 2   ? VelocityProxy::kAuto
                       : state.range(0) == 1 ? VelocityProxy::kDisplacement
                                             : VelocityProxy::kVelocity;
  auto det = std::make_unique<ContactDetector>();
  auto cs = std::make_unique<ContactSet>();
  auto me = std::make_unique<MotionEstimator>();
  me->configure(cal);
  det->detect(s.pad[0]->fz, s.pad[0]->w_now, s.pad[0]->valid, *cs);
  SensorMotion out;
  for (auto _ : state) {
    me->update(*cs, s.pad[0]->shear_now, kDt, out);
    benchmark::DoNotOptimize(out.omega.data());
  }
}
BENCHMARK(BM_MotionUpdate)->Arg(0)->Arg(1)->Arg(2)->ArgName("proxy");

void BM_Solve3(benchmark::State& state) {
  Eigen::Matrix3d A;
  A << 4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0;
  Eigen::Vector3d b(1.0, -2.0, 0.5);
  for (auto _ : state) {
    benchmark::DoNotOptimize(A.data());
    const Solve3Result r = solve3(A, b);
    benchmark::DoNotOptimize(r.x.data());
  }
}
BENCHMARK(BM_Solve3);

void BM_Fuse(benchmark::State& state) {
  const Scene& s = scene();
  SensorMotion m[2];
  for (int i = 0; i < 2; ++i) {
    auto det = std::make_unique<ContactDetector>();
    auto cs = std::make_unique<ContactSet>();
    auto me = std::make_unique<MotionEstimator>();
    det->detect(s.pad[i]->fz, s.pad[i]->w_prev, s.pad[i]->valid, *cs);
    me->update(*cs, s.pad[i]->shear_prev, kDt, m[i]);
    det->detect(s.pad[i]->fz, s.pad[i]->w_now, s.pad[i]->valid, *cs);
    me->update(*cs, s.pad[i]->shear_now, kDt, m[i]);
  }
  FusionConfig cfg;
  cfg.method = state.range(0) != 0 ? FusionMethod::kJoint : FusionMethod::kPaper;
  FusedMotion out;
  for (auto _ : state) {
    fuse(&m[0], &m[1], cfg, kW, out);
    benchmark::DoNotOptimize(out.xi.data());
  }
}
BENCHMARK(BM_Fuse)->Arg(0)->Arg(1)->ArgName("joint");

void BM_Se3IntegrateSpatial(benchmark::State& state) {
  PoseIntegrator integ;
  Vector6d xi;
  xi << 0.3, -0.2, 0.4, 4e-3, -3e-3, 0.0;
  for (auto _ : state) {
    integ.step_spatial(xi, kDt);
    benchmark::DoNotOptimize(integ.pose().p.data());
  }
}
BENCHMARK(BM_Se3IntegrateSpatial);

void BM_MovingAverage(benchmark::State& state) {
  MovingAverage<> ma(static_cast<int>(state.range(0)));
  Vector6d xi;
  xi << 0.3, -0.2, 0.4, 4e-3, -3e-3, 0.0;
  for (auto _ : state) {
    xi(0) += 1e-9;
    benchmark::DoNotOptimize(ma.push(xi).data());
  }
}
BENCHMARK(BM_MovingAverage)->Arg(4)->Arg(kMaxMovingAverage)->ArgName("L");

// The whole back end for one frame pair: per pad force map + contact + motion, then fusion,
// moving average and SE(3) integration.
void BM_BackEndFramePair(benchmark::State& state) {
  const Scene& s = scene();
  FusionConfig cfg;
  cfg.method = state.range(0) != 0 ? FusionMethod::kJoint : FusionMethod::kPaper;
  ForceMap fm;
  auto det = std::make_unique<ContactDetector[]>(2);
  auto me = std::make_unique<MotionEstimator[]>(2);
  auto cs = std::make_unique<ContactSet>();
  auto fz = std::make_unique<ScalarField>();
  auto shear = std::make_unique<VectorField>();
  MovingAverage<> ma(4);
  PoseIntegrator integ;
  SensorMotion m[2];
  FusedMotion out;
  for (auto _ : state) {
    for (int i = 0; i < 2; ++i) {
      fm.compute(s.density, s.d, s.r, s.k, s.pad[i]->valid, *fz, *shear);
      benchmark::DoNotOptimize(fz->v.data());
      // Contact and motion run on the scene's own f^z and shear so the contact is realistic.
      det[i].detect(s.pad[i]->fz, s.pad[i]->w_now, s.pad[i]->valid, *cs);
      me[i].update(*cs, s.pad[i]->shear_now, kDt, m[i]);
    }
    fuse(&m[0], &m[1], cfg, kW, out);
    integ.step_spatial(ma.push(out.xi), kDt);
    benchmark::DoNotOptimize(integ.pose().p.data());
  }
}
BENCHMARK(BM_BackEndFramePair)->Arg(0)->Arg(1)->ArgName("joint");

}  // namespace

BENCHMARK_MAIN();
