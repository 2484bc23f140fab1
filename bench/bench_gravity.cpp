// The gravity and accelerometer-bias solve of the paper pipeline (GravityEstimator) over a window
// of 100 kinematic samples (0.5 s at 200 Hz) of an exact rotational motion with velocimeter and
// accelerometer noise: body + LiDAR equations, covariance included, in both formulations.
#include <benchmark/benchmark.h>

#include <random>
#include <stdexcept>
#include <vector>

#include "analytic_motion.h"
#include "paper/gravity_estimator.h"

namespace {

using namespace freeinit;

struct Window {
  std::vector<KinematicSample> samples;
  Extrinsics extrinsics;
};

/// `n` samples at 200 Hz, white noise sigma_v on v_b and v_l, sigma_a on the accelerometer.
Window makeWindow(int n, double sigma_v, double sigma_a) {
  std::mt19937 rng(1);
  std::normal_distribution<double> n01(0.0, 1.0);
  auto noise3 = [&](double s) { return Vec3(s * n01(rng), s * n01(rng), s * n01(rng)); };
  const test::AnalyticMotion motion(1.0);
  Window w;
  w.extrinsics = test::testExtrinsics();
  const Vec3 g_world(0, 0, -kGravity), b_a(0.1, -0.15, 0.08);
  const Mat3 R_w0_w = motion.at(0).R_wb.transpose();
  for (int k = 0; k < n; ++k) {
    const test::MotionState m = motion.at(k / 200.0);
    KinematicSample s;
    s.t = k / 200.0;
    s.R_wb = R_w0_w * m.R_wb;
    const Vec3 v_b = m.R_wb.transpose() * m.v_w;
    s.v_b = v_b + noise3(sigma_v);
    s.cov_v_b = sigma_v * sigma_v * Mat3::Identity();
    s.omega_b = m.omega_b;
    s.v_l = w.extrinsics.R_bl.transpose() * (v_b + m.omega_b.cross(w.extrinsics.p_bl)) +
            noise3(sigma_v);
    s.cov_v_l = s.cov_v_b;
    s.accel = m.R_wb.transpose() * (m.a_w - g_world) + b_a + noise3(sigma_a);
    w.samples.push_back(s);
  }
  return w;
}

void BM_GravitySolve(benchmark::State& state, GravityEstimator::Formulation f) {
  const Window w = makeWindow(static_cast<int>(state.range(0)), 0.02, 0.02);
  GravityParams p;
  p.formulation = f;
  p.accel_sigma = 0.02;
  const GravityEstimator est(p);
  for (auto _ : state) {
    const GravityEstimate e = est.estimate(w.samples, w.extrinsics);
    if (!e.ok) throw std::runtime_error("the gravity solve failed on the benchmark window");
    benchmark::DoNotOptimize(e.g_w);
  }
}

BENCHMARK_CAPTURE(BM_GravitySolve, integrated, GravityEstimator::Formulation::Integrated)
    ->Arg(100)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_GravitySolve, differentiated, GravityEstimator::Formulation::Differentiated)
    ->Arg(100)
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
