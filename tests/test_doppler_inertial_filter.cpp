// The joint window estimator's models and filter on a closed-form motion: the IMU interpolation
// and integration against the exact motion, the Jacobians against finite differences, and the
// whole filter and smoother against the truth and its own covariance, with a calibration that is
// right and one that is not.
#include <freeinit/rotation.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "analytic_motion.h"
#include "joint/doppler_inertial_filter.h"

namespace freeinit {
namespace {

using Filter = DopplerInertialFilter;

constexpr double kT0 = 100.0;       // [s] the recording's first IMU time
constexpr double kImuRate = 200.0;  // [Hz]
const Vec3 kGravityW(0, 0, -kGravity);
constexpr double kDeg = 3.14159265358979323846 / 180.0;

struct Noise {
  double gyro = 0, accel = 0, doppler = 0;
};
const Vec3 kBg(0.004, -0.003, 0.005);  // [rad/s] within the default prior (0.015)
const Vec3 kBa(0.05, -0.04, 0.03);     // [m/s^2] within the default prior (0.1)

/// IMU samples of the motion from kT0 over `duration`, with the biases above and white noise.
std::vector<ImuSample> imuOf(const test::AnalyticMotion& m, double duration, const Noise& noise,
                             std::mt19937& rng) {
  std::normal_distribution<double> n01;
  auto noisy = [&](double sigma) -> Vec3 { return Vec3(n01(rng), n01(rng), n01(rng)) * sigma; };
  std::vector<ImuSample> imu;
  const int n = static_cast<int>(std::lround(duration * kImuRate)) + 1;
  for (int i = 0; i < n; ++i) {
    const double t = i / kImuRate;
    const test::MotionState s = m.at(t);
    ImuSample smp;
    smp.t = kT0 + t;
    smp.gyro = s.omega_b + kBg + noisy(noise.gyro);
    smp.accel = s.R_wb.transpose() * (s.a_w - kGravityW) + kBa + noisy(noise.accel);
    imu.push_back(smp);
  }
  return imu;
}

/// The exact state at sample k (biases as simulated, calibration as declared).
FilterState truthAt(const test::AnalyticMotion& m, const std::vector<ImuSample>& imu,
                    std::size_t k) {
  const test::MotionState s = m.at(imu[k].t - kT0);
  FilterState x;
  x.t = imu[k].t;
  x.R_wb = s.R_wb;
  x.p_w = s.p_w;
  x.v_w = s.v_w;
  x.b_g = kBg;
  x.b_a = kBa;
  return x;
}

TEST(DopplerInertialFilter, InterpolationIsExactForCubicRates) {
  // Irregular sample times (a jittery IMU clock). Between the inner samples the interpolation
  // runs through four samples and reproduces any cubic exactly; in the first and the last
  // interval it has three, and reproduces quadratics.
  auto cubic = [](double t) -> Vec3 {
    return Vec3(1 - 2 * t + 3e3 * t * t * t, 0.5 * t * t, -t + 2e4 * t * t * t);
  };
  auto quadratic = [](double t) -> Vec3 { return Vec3(1 - 2 * t, 50 * t * t, -t + 3e2 * t * t); };
  for (const bool inner : {true, false}) {
    const auto f = [&](double t) -> Vec3 { return inner ? cubic(t) : quadratic(t); };
    std::vector<ImuSample> imu;
    for (double t : {0.0, 0.004, 0.0105, 0.015, 0.0212, 0.025}) {
      ImuSample s;
      s.t = t;
      s.gyro = f(t);
      s.accel = 2.0 * f(t);
      imu.push_back(s);
    }
    const std::vector<double> times =
        inner ? std::vector<double>{0.007, 0.0123, 0.018} : std::vector<double>{0.001, 0.0249};
    for (double t : times) {
      Vec3 g, a;
      Filter::interpolateImu(imu, t, g, a);
      EXPECT_LT((g - f(t)).norm(), 1e-12) << t;
      EXPECT_LT((a - 2.0 * f(t)).norm(), 1e-12) << t;
    }
  }
}

TEST(DopplerInertialFilter, TheMotionsLinesFromRunningSumsAreTheSummedOnes) {
  // A 2 kHz IMU with a jittery clock at a Unix-epoch time, its motion bent by a vibration whose
  // amplitude grows over the second (so that lines hold over some spans and not others), and
  // white noise. motionAt() from the running sums (two differences per span) against the same
  // sums gathered sample by sample: the same verdicts, the same lines but for rounding. The
  // differences lose about five of sixteen digits (a span's sum of d^2 against the running sum
  // of u^2 over a second): 1e-9 of the values' size is well clear of it.
  std::mt19937 rng(5);
  std::normal_distribution<double> n01;
  std::uniform_real_distribution<double> jitter(-1e-5, 1e-5);
  const double t0 = 1.7e9;
  std::vector<ImuSample> imu;
  for (int i = 0; i <= 2000; ++i) {
    const double t = i / 2000.0 + jitter(rng);
    const double vib = 2.0 * t * std::sin(2 * 3.14159265358979323846 * 30 * t);
    ImuSample smp;
    smp.t = t0 + t;
    smp.gyro = Vec3(0.3 * t, -0.2, 0.1 * vib) + 0.002 * Vec3(n01(rng), n01(rng), n01(rng));
    smp.accel = Vec3(0.5 + vib, 0.2 * t, 9.81) + 0.02 * Vec3(n01(rng), n01(rng), n01(rng));
    imu.push_back(smp);
  }
  std::vector<Filter::RunningSums> running;
  Filter::extendRunningSums(imu, running);
  ASSERT_EQ(running.size(), imu.size() + 1);
  int lines = 0, bends = 0;
  for (int i = 0; i < 500; ++i) {
    const double t = t0 + i / 499.0;
    Vec3 a_sum, r_sum, a_run, r_run;
    const bool sum = Filter::motionAt(imu, t, imu.size(), 0.002, 0.02, a_sum, r_sum);
    const bool run =
        Filter::motionAt(imu, t, imu.size(), 0.002, 0.02, a_run, r_run, nullptr, &running);
    ASSERT_EQ(sum, run) << "at " << i;
    (sum ? lines : bends) += 1;
    EXPECT_LT((a_run - a_sum).norm(), 1e-9 * (1 + a_sum.norm())) << "at " << i;
    EXPECT_LT((r_run - r_sum).norm(), 1e-9 * (1 + r_sum.norm())) << "at " << i;
  }
  EXPECT_GT(lines, 50);
  EXPECT_GT(bends, 50);
}

TEST(DopplerInertialFilter, IntegrationFollowsTheExactMotion) {
  // Noise-free samples of a 3-4 rad/s rotating, accelerating motion, integrated step by step for
  // 0.5 s from the exact start. The drift must stay far below what the window's data resolve
  // (the randomized scenarios' bounds are >= 0.05 deg and >= 0.002 m/s): a hundredth of those.
  const test::AnalyticMotion m;
  std::mt19937 rng(1);
  const auto imu = imuOf(m, 0.6, {}, rng);
  FilterState x = truthAt(m, imu, 0);
  for (std::size_t k = 0; k + 1 < 101; ++k) x = Filter::propagate(x, imu, k);
  const FilterState t = truthAt(m, imu, 100);
  EXPECT_NEAR(x.t, t.t, 1e-12);
  EXPECT_LT(Log(t.R_wb.transpose() * x.R_wb).norm(), 0.05 * kDeg / 100);
  EXPECT_LT((x.v_w - t.v_w).norm(), 0.002 / 100);
  EXPECT_LT((x.p_w - t.p_w).norm(), 1e-4);
  // Within an interval too (the points' times).
  const FilterState y = Filter::integrate(truthAt(m, imu, 40), imu, 40, 0.0031);
  const test::MotionState s = m.at(imu[40].t + 0.0031 - kT0);
  EXPECT_LT(Log(s.R_wb.transpose() * y.R_wb).norm(), 1e-7);
  EXPECT_LT((y.v_w - s.v_w).norm(), 1e-6);
}

/// A state away from the truth in every block, so that no Jacobian term vanishes.
FilterState offState(const test::AnalyticMotion& m, const std::vector<ImuSample>& imu,
                     std::size_t k) {
  FilterState x = truthAt(m, imu, k);
  x.R_wb = x.R_wb * Exp(Vec3(0.05, -0.03, 0.02));
  x.v_w += Vec3(0.2, -0.1, 0.05);
  x.b_g += Vec3(0.01, 0.02, -0.01);
  x.b_a += Vec3(0.1, -0.2, 0.1);
  x.phi_bl = Vec3(0.01, -0.02, 0.015);
  x.dt_l = 0.002;
  return x;
}

TEST(DopplerInertialFilter, TransitionJacobianMatchesFiniteDifferences) {
  const test::AnalyticMotion m;
  std::mt19937 rng(2);
  const auto imu = imuOf(m, 0.2, {0.002, 0.02, 0}, rng);
  for (std::size_t k : {1u, 17u, 30u}) {
    const FilterState x = offState(m, imu, k);
    const Filter::MatS F = Filter::transitionJacobian(x, imu, k);
    const Filter::MatS Fn = Filter::numericalTransitionJacobian(x, imu, k);
    // The analytic form is first order in the step (5 ms): its terms of order dt^2 |omega|^2
    // (~1e-4 of the leading ones) are what it leaves out; finite differences are exact to ~1e-9.
    EXPECT_LT((F - Fn).cwiseAbs().maxCoeff(), 2e-4) << "sample " << k << "\n" << (F - Fn);
  }
}

TEST(DopplerInertialFilter, LidarVelocityJacobianMatchesFiniteDifferences) {
  // A brisk motion (accelerations of ~10 m/s^2 changing within milliseconds): the clock
  // offset's column is the interpolant's rate there too (motionAt()), as the other columns.
  const test::AnalyticMotion m;
  std::mt19937 rng(3);
  const auto imu = imuOf(m, 0.2, {0.002, 0.02, 0}, rng);
  const Filter filter({}, test::testExtrinsics());
  for (double tau : {-0.0021, 0.0, 0.0013}) {
    const std::size_t k = 20;
    const FilterState x = offState(m, imu, k);
    Eigen::Matrix<double, 3, Filter::kStateDim> J;
    filter.lidarVelocity(x, imu, k, tau, &J);
    constexpr double h = 1e-6;
    for (int i = 0; i < Filter::kStateDim; ++i) {
      Filter::VecS e = Filter::VecS::Zero();
      e(i) = h;
      const Vec3 d = (filter.lidarVelocity(Filter::boxplus(x, e), imu, k, tau) -
                      filter.lidarVelocity(Filter::boxplus(x, -e), imu, k, tau)) /
                     (2 * h);
      // Relative to the column's size (lever-arm and bias columns are ~0.1-1, the time column
      // ~10 m/s^2): the integration Jacobian is first order in tau (<= 2.5 ms).
      EXPECT_LT((J.col(i) - d).norm(), 1e-3 * std::max(1.0, d.norm()))
          << "column " << i << " tau " << tau << ": " << J.col(i).transpose() << " vs "
          << d.transpose();
    }
  }
}

TEST(DopplerInertialFilter, IntegrationAcrossSamplesComposesTheSteps) {
  // Nodes at a bounded rate integrate across several samples: one step per sample interval, the
  // last one partial, the Jacobians composed. Over whole intervals it is the steps' propagation;
  // its Jacobian matches finite differences (each step's analytic one is first order: ~2e-4 of
  // the leading terms per 5 ms step, here up to six steps); and it follows the exact motion.
  const test::AnalyticMotion m;
  std::mt19937 rng(4);
  const auto imu = imuOf(m, 0.3, {0.002, 0.02, 0}, rng);
  const auto exact = imuOf(m, 0.3, {}, rng);
  const std::size_t k = 20;
  {
    const FilterState x = offState(m, imu, k);
    FilterState y = x;
    for (std::size_t j = k; j < k + 5; ++j) y = Filter::propagate(y, imu, j);
    const FilterState z = Filter::integrateAcross(x, imu, k, imu[k + 5].t - imu[k].t);
    EXPECT_LT(Filter::boxminus(z, y).norm(), 1e-12);
  }
  for (double tau : {0.0265, -0.017, 0.0013, imu[k + 4].t - imu[k].t}) {
    const FilterState x = offState(m, imu, k);
    Filter::MatS J;
    const FilterState y = Filter::integrateAcross(x, imu, k, tau, &J);
    constexpr double h = 1e-6;
    for (int i = 0; i < Filter::kStateDim; ++i) {
      Filter::VecS e = Filter::VecS::Zero();
      e(i) = h;
      const Filter::VecS d =
          (Filter::boxminus(Filter::integrateAcross(Filter::boxplus(x, e), imu, k, tau), y) -
           Filter::boxminus(Filter::integrateAcross(Filter::boxplus(x, -e), imu, k, tau), y)) /
          (2 * h);
      EXPECT_LT((J.col(i) - d).norm(), 1.5e-3 * std::max(1.0, d.norm()))
          << "column " << i << " tau " << tau << ": " << J.col(i).transpose() << " vs "
          << d.transpose();
    }
    const FilterState t = Filter::integrateAcross(truthAt(m, exact, k), exact, k, tau);
    const test::MotionState s = m.at(imu[k].t + tau - kT0);
    EXPECT_LT(Log(s.R_wb.transpose() * t.R_wb).norm(), 1e-6) << tau;
    EXPECT_LT((t.v_w - s.v_w).norm(), 1e-5) << tau;
    EXPECT_LT((t.p_w - s.p_w).norm(), 1e-6) << tau;
  }
}

TEST(DopplerInertialFilter, IntegrationBackThroughTheNodeBeforeMatchesTheStepsBack) {
  // A node integrates back to its fit instant before it through the preintegrations forward of
  // the node before (each sample integrated once): the same motion as the steps back, to the
  // integration's own order and the second order of the bias change since the chain was made
  // (here 0.01 rad/s and 0.1 m/s^2 over 25 ms: the first order would leave ~1e-4 rad and
  // ~1e-3 m/s); its Jacobian matches finite differences. A chain made at biases too far away
  // is not read: the node's own chain back gives the steps' result (split at the sample nearest
  // the end rather than at the last one reached: 2e-8).
  const test::AnalyticMotion m;
  std::mt19937 rng(4);
  const auto imu = imuOf(m, 0.3, {0.002, 0.02, 0}, rng);
  const std::size_t k_before = 20, k = 25;
  const FilterState x = offState(m, imu, k);
  FilterState x_before = x;
  x_before.b_g += Vec3(0.01, -0.008, 0.005);
  x_before.b_a += Vec3(0.1, -0.05, 0.08);
  for (double tau : {0.5 * (imu[k_before].t - imu[k].t), imu[k - 2].t - imu[k].t, -0.0021}) {
    bool through = false;
    Filter::MatS J;
    const FilterState y =
        Filter::integrateBackThrough(x, imu, k_before, k, tau, x_before, &J, &through);
    EXPECT_TRUE(through);
    const FilterState z = Filter::integrateAcross(x, imu, k, tau);
    EXPECT_LT(Log(z.R_wb.transpose() * y.R_wb).norm(), 1e-8) << tau;  // 6e-10 at most
    EXPECT_LT((y.v_w - z.v_w).norm(), 5e-7) << tau;                   // 8e-8
    EXPECT_LT((y.p_w - z.p_w).norm(), 2e-8) << tau;                   // 4e-9
    constexpr double h = 1e-6;
    for (int i = 0; i < Filter::kStateDim; ++i) {
      Filter::VecS e = Filter::VecS::Zero();
      e(i) = h;
      auto at = [&](const Filter::VecS& dx) {
        return Filter::integrateBackThrough(Filter::boxplus(x, dx), imu, k_before, k, tau,
                                            x_before);
      };
      const Filter::VecS d = (Filter::boxminus(at(e), y) - Filter::boxminus(at(-e), y)) / (2 * h);
      EXPECT_LT((J.col(i) - d).norm(), 1.5e-3 * std::max(1.0, d.norm()))
          << "column " << i << " tau " << tau << ": " << J.col(i).transpose() << " vs "
          << d.transpose();
    }
  }
  x_before.b_g += Vec3::Constant(0.1);  // 2.5e-3 rad over the chain's 25 ms
  bool through = true;
  const double tau = 0.5 * (imu[k_before].t - imu[k].t);
  const FilterState y =
      Filter::integrateBackThrough(x, imu, k_before, k, tau, x_before, nullptr, &through);
  EXPECT_FALSE(through);
  EXPECT_LT(Filter::boxminus(y, Filter::integrateAcross(x, imu, k, tau)).norm(), 1e-7);
}

TEST(DopplerInertialFilter, TheClockOffsetsColumnIsTheMotionsNotTheNoises) {
  // A gentle motion (accelerations of ~0.3 m/s^2, 0.1 rad/s) and an IMU noisy as a MEMS unit
  // (0.002 rad/s, 0.04 m/s^2 per sample): the column from the samples' own interpolant is off
  // by their noise, sqrt(3) 0.04 m/s^2 RMS from the accelerometer alone (0.13 measured). The
  // fit's over +-25 ms (11 samples at 200 Hz) is off by 1/sqrt(11) of it, 0.021 m/s^2, and
  // the gyro's slope (0.04 rad/s^2 per axis) adds ~0.004 through the lever arm: RMS over 60
  // cases within 0.03.
  const test::AnalyticMotion m(0.03);
  DopplerInertialFilterParams p;
  p.gyro_sigma = 0.002;
  p.accel_sigma = 0.04;
  const Filter filter(p, test::testExtrinsics());
  std::mt19937 none(5);
  const auto exact = imuOf(m, 0.3, {}, none);
  double sum2 = 0;
  int cases = 0;
  for (unsigned seed = 0; seed < 20; ++seed) {
    std::mt19937 rng(100 + seed);
    const auto noisy = imuOf(m, 0.3, {0.002, 0.04, 0}, rng);
    for (std::size_t k : {10u, 30u, 50u}) {
      const FilterState x = truthAt(m, exact, k);
      Eigen::Matrix<double, 3, Filter::kStateDim> J, Jn;
      filter.lidarVelocity(x, exact, k, 0.001, &J);
      filter.lidarVelocity(x, noisy, k, 0.001, &Jn);
      sum2 += (Jn.col(Filter::kTime) - J.col(Filter::kTime)).squaredNorm();
      ++cases;
    }
  }
  EXPECT_LT(std::sqrt(sum2 / cases), 0.03);
}

TEST(DopplerInertialFilter, BoxMinusUndoesBoxPlus) {
  const test::AnalyticMotion m;
  std::mt19937 rng(4);
  const auto imu = imuOf(m, 0.1, {}, rng);
  const FilterState x = offState(m, imu, 5);
  Filter::VecS dx;
  for (int i = 0; i < Filter::kStateDim; ++i) dx(i) = 0.01 * (i % 5) - 0.02;
  EXPECT_LT((Filter::boxminus(Filter::boxplus(x, dx), x) - dx).norm(), 1e-12);
}

/// A window of Doppler returns of the motion, spread uniformly over directions and time, with
/// Doppler noise; `time_offset`: the LiDAR clock runs this much ahead of the IMU's (undeclared).
struct Returns {
  std::vector<double> t;  // LiDAR clock
  std::vector<Eigen::Vector3f> p_l;
  std::vector<double> z;
};
Returns returnsOf(const test::AnalyticMotion& m, double t_end, std::size_t n, double sigma,
                  double time_offset, std::mt19937& rng) {
  const Extrinsics e = test::testExtrinsics();
  std::uniform_real_distribution<double> u01(0, 1);
  std::normal_distribution<double> n01;
  std::vector<double> times(n);
  for (double& t : times) t = kT0 + t_end * u01(rng);
  std::sort(times.begin(), times.end());
  Returns r;
  for (double t_true : times) {
    const Vec3 d = Vec3(n01(rng), n01(rng), n01(rng)).normalized();
    const test::MotionState s = m.at(t_true - kT0);
    const Vec3 v_l = e.R_bl.transpose() * (s.R_wb.transpose() * s.v_w + s.omega_b.cross(e.p_bl));
    r.t.push_back(t_true + time_offset);
    r.p_l.push_back((d * (5.0 + 20.0 * u01(rng))).cast<float>());
    r.z.push_back(-d.dot(v_l) + sigma * n01(rng));
  }
  return r;
}

/// One node's returns as the filter takes them (DopplerInertialFilter::setReturns), laid out as
/// the pipeline's recorder lays them out: tau from the node time, position in the LiDAR frame and
/// Doppler, each rounded to float. Held until the node's update() returns.
struct NodeArrays {
  std::vector<float> tau, x, y, z, doppler;
  void clear() {
    for (std::vector<float>* v : {&tau, &x, &y, &z, &doppler}) v->clear();
  }
  void add(double tau_s, const Eigen::Vector3f& p_l, double doppler_mps) {
    tau.push_back(static_cast<float>(tau_s));
    x.push_back(p_l.x());
    y.push_back(p_l.y());
    z.push_back(p_l.z());
    doppler.push_back(static_cast<float>(doppler_mps));
  }
  Filter::OpenArrays arrays() const {
    return {tau.size(), tau.data(), x.data(), y.data(), z.data(), doppler.data()};
  }
};

struct WindowRun {
  Filter filter;
  FilterState truth;     // at the last node
  int final_iterations;  // of the last smoothing
};

/// Runs the filter and smoother over [kT0, kT0 + 0.5 s] as the pipeline does, from a start that is
/// 2 deg and 0.15 m/s off the truth; with `smooth_at` > 0, smoothing also once after that node
/// (the pipeline's early smoothing; `ahead` as the pipeline gives it) and going on from there.
/// `after_update`, if given, is called with each node's index after its update. `time_sigma` [s],
/// `rotation_sigma` [rad]: the calibration's prior (0: exact).
WindowRun runWindow(const test::AnalyticMotion& m, const std::vector<ImuSample>& imu,
                    const Returns& ret, const Noise& noise, std::size_t smooth_at = 0,
                    bool ahead = true,
                    const std::function<void(Filter&, std::size_t)>& after_update = {},
                    double time_sigma = 0, double rotation_sigma = 0) {
  DopplerInertialFilterParams params;
  params.doppler_sigma = noise.doppler;
  params.gyro_sigma = noise.gyro;
  params.accel_sigma = noise.accel;
  WindowRun run{Filter(params, test::testExtrinsics()), {}, 0};
  Filter& f = run.filter;
  const std::size_t k_last = 100;  // 0.5 s
  std::size_t fed = 0;
  auto feed = [&](std::size_t last) {
    while (fed <= last && fed < imu.size()) f.addImu(imu[fed++]);
  };
  feed(2);
  FilterState x0 = truthAt(m, imu, 0);
  x0.R_wb = Exp(Vec3(0.025, -0.025, 0)) * x0.R_wb;  // 2 deg of tilt
  x0.v_w += x0.R_wb * Vec3(0.1, -0.1, 0.05);
  x0.b_g.setZero();
  x0.b_a.setZero();
  Filter::StartPrior prior;
  prior.cov_v_b = Mat3::Identity() * 0.3 * 0.3;
  prior.time_sigma = time_sigma;
  prior.rotation_sigma = rotation_sigma;
  f.start(x0, prior);
  std::size_t cursor = 0;
  NodeArrays node;
  for (std::size_t k = 0;; ++k) {
    const bool last = k == k_last;
    feed(last ? k + 1 : k + 2);
    f.beginNode(last);
    const double t_k = imu[k].t;
    const double lo = t_k - f.intervalBefore(), hi = t_k + f.intervalAfter();
    node.clear();
    for (; cursor < ret.t.size(); ++cursor) {
      const double t = ret.t[cursor];
      if (last ? t > t_k : t >= hi) break;
      if (t >= lo) node.add(t - t_k, ret.p_l[cursor], ret.z[cursor]);
    }
    f.setReturns(node.arrays());
    f.update();
    if (after_update) after_update(f, k);
    if (last) break;
    if (k == smooth_at && smooth_at > 0) f.smooth(1.0, ahead);
    f.predict();
  }
  run.final_iterations = f.smooth();
  run.truth = truthAt(m, imu, k_last);
  return run;
}

/// Runs the filter over the window's returns with the gates wide open and without the second
/// gate, giving only the returns with keep[i] (all when `remove_after`, and then taking the others
/// back with removePoint() once the window is in; after a first smoothing that looks ahead if
/// `smooth_first`), and smooths.
Filter filterWithout(const test::AnalyticMotion& m, const std::vector<ImuSample>& imu,
                     const Returns& ret, const std::vector<bool>& keep, bool remove_after,
                     bool smooth_first = false) {
  DopplerInertialFilterParams params;
  params.gate_sigma = 50;
  params.gate_min = 5;
  params.regate_sigma = 0;
  Filter f(params, test::testExtrinsics());
  for (const ImuSample& s : imu) f.addImu(s);
  f.start(truthAt(m, imu, 0), Filter::StartPrior{});
  struct Given {
    std::size_t node, index;
    double tau;
  };
  std::vector<Given> taken_back;
  std::size_t cursor = 0;
  const std::size_t k_last = 100;
  NodeArrays node;
  for (std::size_t k = 0;; ++k) {
    const bool last = k == k_last;
    f.beginNode(last);
    const double t_k = imu[k].t;
    const double lo = t_k - f.intervalBefore(), hi = t_k + f.intervalAfter();
    node.clear();
    for (; cursor < ret.t.size(); ++cursor) {
      const double t = ret.t[cursor];
      if (last ? t > t_k : t >= hi) break;
      if (t < lo || (!keep[cursor] && !remove_after)) continue;
      node.add(t - t_k, ret.p_l[cursor], ret.z[cursor]);
      if (!keep[cursor]) taken_back.push_back({k, cursor, t - t_k});
    }
    f.setReturns(node.arrays());
    f.update();
    if (last) break;
    f.predict();
  }
  if (smooth_first) f.smooth(1.0, true);
  for (const Given& g : taken_back) f.removePoint(g.node, g.tau, ret.p_l[g.index], ret.z[g.index]);
  f.smooth();
  return f;
}

/// Every third return of a window taken back (filterWithout; after a first smoothing if
/// `smooth_first`), against a filter that never saw them: the sums are the same up to rounding,
/// so the smoothed states agree to the smoother's tolerances (1e-4 m/s, 1e-5 rad/s; the two got
/// there by different paths).
void expectTakenBackAsNeverGiven(bool smooth_first) {
  const test::AnalyticMotion m;
  const Noise noise{0.002, 0.02, 0.03};
  std::mt19937 rng(21);
  const auto imu = imuOf(m, 0.6, noise, rng);
  const Returns ret = returnsOf(m, 0.5, 6000, noise.doppler, 0.0, rng);
  std::vector<bool> keep(ret.t.size());
  for (std::size_t i = 0; i < keep.size(); ++i) keep[i] = i % 3 != 0;
  const Filter a = filterWithout(m, imu, ret, keep, true, smooth_first);
  const Filter b = filterWithout(m, imu, ret, keep, false);
  ASSERT_EQ(a.nodes(), b.nodes());
  EXPECT_EQ(a.acceptedPointsTotal(), b.acceptedPointsTotal());
  EXPECT_GT(a.acceptedPointsTotal(), 3900u);
  const FilterState& xa = a.state(a.nodes() - 1);
  const FilterState& xb = b.state(b.nodes() - 1);
  EXPECT_LT((xa.v_w - xb.v_w).norm(), 3e-4);
  EXPECT_LT((xa.b_g - xb.b_g).norm(), 3e-5);
  EXPECT_LT((xa.b_a - xb.b_a).norm(), 3e-3);
  EXPECT_NEAR(a.residualSumOfSquares(), b.residualSumOfSquares(), 1e-3 * b.residualSumOfSquares());
}

// A sample interpolated in place of a fault or a gap (ImuScreen) adds the variance of its
// interpolation's error to the white noise the filter uses, whatever that is (the configured one
// or the data's): at rest, with R_wb = I, the two steps touching sample 3 each add it times dt^2
// to the velocity's variance per axis, and nothing else changes.
TEST(DopplerInertialFilter, ASyntheticSampleAddsItsVarianceToWhicheverWhiteNoise) {
  constexpr double kDt = 0.005, kExtra = 0.3;  // [s], [(m/s^2)^2]
  auto velocityVariance = [&](double accel_sigma, double extra) {
    DopplerInertialFilterParams params;
    params.accel_sigma = accel_sigma;
    Filter f(params, test::testExtrinsics());
    for (std::size_t k = 0; k < 12; ++k) {
      ImuSample s;
      s.t = 10.0 + kDt * static_cast<double>(k);
      s.accel = Vec3(0, 0, kGravity);
      f.addImu(s, 0.0, k == 3 ? extra : 0.0);
    }
    FilterState x0;
    x0.t = 10.0;
    f.start(x0, Filter::StartPrior{});
    NodeArrays none;
    for (std::size_t k = 0; k < 6; ++k) {
      f.beginNode(false);
      f.setReturns(none.arrays());
      f.update();
      f.predict();
    }
    return f.covariance().block<3, 3>(Filter::kVel, Filter::kVel).eval();
  };
  for (const double sigma : {0.02, 0.2}) {
    const Mat3 added = velocityVariance(sigma, kExtra) - velocityVariance(sigma, 0.0);
    EXPECT_LT((added - 2.0 * kExtra * kDt * kDt * Mat3::Identity()).norm(),
              1e-6 * kExtra * kDt * kDt)
        << sigma << "\n"
        << added;
  }
}

TEST(DopplerInertialFilter, TakingPointsBackEqualsNeverGivingThem) {
  // Taken back after the window.
  expectTakenBackAsNeverGiven(false);
}

TEST(DopplerInertialFilter, TakingPointsBackAfterASmoothingEqualsNeverGivingThem) {
  // Smoothed (looking ahead: the forward pass of the next smoothing made and kept), the returns
  // taken back, smoothed again. The kept forward pass holds only before the first node that lost
  // a return; taken for the others, the second smoothing would find its first step below the
  // tolerances and keep the answer with the returns.
  expectTakenBackAsNeverGiven(true);
}

/// Squared Mahalanobis distance of the estimate's error in attitude, velocity and both biases.
double nees12(const WindowRun& r) {
  const Filter& f = r.filter;
  const Filter::VecS e = Filter::boxminus(r.truth, f.state(f.nodes() - 1));
  Eigen::Matrix<double, 12, 1> d;
  d << e.segment<3>(Filter::kTheta), e.segment<3>(Filter::kVel), e.segment<3>(Filter::kBg),
      e.segment<3>(Filter::kBa);
  Eigen::Matrix<double, 12, 12> P;
  const std::array<int, 4> blocks = {Filter::kTheta, Filter::kVel, Filter::kBg, Filter::kBa};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      P.block<3, 3>(3 * i, 3 * j) = f.covariance().block<3, 3>(blocks[i], blocks[j]);
  return d.dot(P.ldlt().solve(d));
}

TEST(DopplerInertialFilter, WindowEstimateIsConsistentWithItsCovariance) {
  // Five noise draws of a rotating start with MEMS-grade noise: every estimate of attitude,
  // velocity and biases lies within the 99.9 % ellipsoid of its own covariance (chi-square, 12
  // dof: 32.9), and the velocity is resolved below 1 cm/s.
  const test::AnalyticMotion m;
  const Noise noise{0.002, 0.02, 0.03};
  for (unsigned seed = 11; seed <= 15; ++seed) {
    std::mt19937 rng(seed);
    const auto imu = imuOf(m, 0.6, noise, rng);
    const Returns ret = returnsOf(m, 0.5, 20000, noise.doppler, 0.0, rng);
    const WindowRun r = runWindow(m, imu, ret, noise);
    const FilterState& x = r.filter.state(r.filter.nodes() - 1);
    EXPECT_LT(nees12(r), 32.9) << "seed " << seed;
    const Filter::MatS& P = r.filter.covariance();
    const double v_bound = 4 * std::sqrt(P.block<3, 3>(Filter::kVel, Filter::kVel).trace());
    EXPECT_LT((x.v_w - r.truth.v_w).norm(), v_bound) << "seed " << seed;
    const Mat3 P_v = P.block<3, 3>(Filter::kVel, Filter::kVel);
    EXPECT_LT(P_v.trace(), 0.01 * 0.01);  // a third of one return's noise
    // The data inform the gyro bias (the rotation ties it to the attitude the Doppler sees):
    // its std falls below the prior's 0.015 rad/s.
    const Mat3 P_bg = P.block<3, 3>(Filter::kBg, Filter::kBg);
    EXPECT_LT(std::sqrt(P_bg.trace() / 3), 0.8 * 0.015);
    // Every return is static and the noise Gaussian: the first gate (4 sigma) keeps them all
    // but a few in ten thousand, the second (3 sigma) all but ~0.3 %.
    EXPECT_GT(r.filter.acceptedPointsTotal(), 19800u) << "seed " << seed;
    const double rms = std::sqrt(r.filter.residualSumOfSquares() /
                                 static_cast<double>(r.filter.acceptedPointsTotal()));
    EXPECT_NEAR(rms, noise.doppler, 0.1 * noise.doppler) << "seed " << seed;
  }
}

/// The same iterations, states and covariance to the bit.
void expectSameSmoothing(const WindowRun& plain, const WindowRun& ahead) {
  EXPECT_EQ(plain.final_iterations, ahead.final_iterations);
  ASSERT_EQ(plain.filter.nodes(), ahead.filter.nodes());
  for (std::size_t k = 0; k < plain.filter.nodes(); ++k) {
    const FilterState &a = plain.filter.state(k), &b = ahead.filter.state(k);
    EXPECT_TRUE(a.R_wb == b.R_wb && a.p_w == b.p_w && a.v_w == b.v_w && a.b_g == b.b_g &&
                a.b_a == b.b_a)
        << "node " << k;
  }
  EXPECT_TRUE(plain.filter.covariance() == ahead.filter.covariance());
}

TEST(DopplerInertialFilter, SmoothingEarlyLeavesTheFinalSmoothingTheSameAnswer) {
  // The pipeline smooths once at 75 % of the window and goes on. The final smoothing then finds
  // the answer of one smoothing over the whole window, and in at most two iterations: the nodes
  // added after the early smoothing start from the propagation of the smoothed ones, a
  // linearization one Gauss-Newton step from the solution. The answers agree within a tenth of
  // the estimate's std in every component: the early smoothing moves the predictions after it,
  // so the first gate may take a few different returns of the 20,000 (each moves the estimate by
  // ~ 1/sqrt(20000) of a std per std of its residual); when it takes the same ones, to rounding.
  // The early smoothing looks ahead, as the pipeline's does: it makes, at the states it leaves,
  // the final smoothing's first forward pass over its nodes, which the final one then takes
  // instead of computing it; one that does not look ahead gives the same, to the bit.
  const test::AnalyticMotion m;
  const Noise noise{0.002, 0.02, 0.03};
  for (unsigned seed = 31; seed <= 33; ++seed) {
    std::mt19937 rng(seed);
    const auto imu = imuOf(m, 0.6, noise, rng);
    const Returns ret = returnsOf(m, 0.5, 20000, noise.doppler, 0.0, rng);
    const WindowRun once = runWindow(m, imu, ret, noise);
    const WindowRun early = runWindow(m, imu, ret, noise, 75);
    EXPECT_LE(early.final_iterations, 2) << "seed " << seed;
    const Filter& f = once.filter;
    const Filter::VecS d =
        Filter::boxminus(f.state(f.nodes() - 1), early.filter.state(early.filter.nodes() - 1));
    const bool same_returns = f.acceptedPointsTotal() == early.filter.acceptedPointsTotal();
    for (int i = 0; i < Filter::kCoreDim; ++i)
      EXPECT_LT(std::abs(d(i)), (same_returns ? 1e-3 : 0.1) * std::sqrt(f.covariance()(i, i)))
          << "seed " << seed << " component " << i;
    SCOPED_TRACE("seed " + std::to_string(seed));
    expectSameSmoothing(runWindow(m, imu, ret, noise, 75, false), early);
  }
}

TEST(DopplerInertialFilter, SmoothingAheadHoldsOnlyWhereTheRestStays) {
  // Rest at the first 80 nodes, then taken back from node 72 on (the motion seen late, after the
  // early smoothing at node 75): the forward pass made ahead holds for nodes 0-71 only, and the
  // final smoothing is again that of an early smoothing that did not look ahead, to the bit.
  const test::AnalyticMotion m;
  const Noise noise{0.002, 0.02, 0.03};
  std::mt19937 rng(33);
  const auto imu = imuOf(m, 0.6, noise, rng);
  const Returns ret = returnsOf(m, 0.5, 20000, noise.doppler, 0.0, rng);
  auto rest = [&imu](Filter& f, std::size_t k) {
    if (k < 80) f.updateRest(1.0, 0.0);  // loose: the sensor moves
    if (k == 80) f.cancelRestFrom(imu[72].t);
  };
  expectSameSmoothing(runWindow(m, imu, ret, noise, 75, false, rest),
                      runWindow(m, imu, ret, noise, 75, true, rest));
}

/// A window's data: the IMU (0.6 s) and 20,000 returns (0.5 s) of the motion drawn with `seed`,
/// the LiDAR clock `offset` [s] ahead of the IMU's.
struct OffsetWindow {
  std::vector<ImuSample> imu;
  Returns ret;
};
OffsetWindow offsetWindow(const test::AnalyticMotion& m, const Noise& noise, double offset,
                          unsigned seed = 21) {
  std::mt19937 rng(seed);
  OffsetWindow w;
  w.imu = imuOf(m, 0.6, noise, rng);
  w.ret = returnsOf(m, 0.5, 20000, noise.doppler, offset, rng);
  return w;
}

TEST(DopplerInertialFilter, CalibrationTestFlagsAnUndeclaredTimeOffset) {
  // The same window with the LiDAR clock 4 ms ahead of the IMU's, declared as synchronized: the
  // calibration test (free calibration std 1 deg, 10 ms) finds a correction far outside what the
  // noise explains (chi-square 4 dof at 99.9 %: 18.5), and recovers the offset. With the clocks
  // in step it does not.
  const test::AnalyticMotion m;
  const Noise noise{0.002, 0.02, 0.03};
  for (double offset : {0.0, 0.004}) {
    const OffsetWindow w = offsetWindow(m, noise, offset);
    const WindowRun r = runWindow(m, w.imu, w.ret, noise);
    const Filter::CalibrationTest c = r.filter.testCalibration(kDeg, 0.01);
    ASSERT_TRUE(c.ok);
    if (offset == 0) {
      EXPECT_LT(c.mahalanobis2, 18.5);
    } else {
      EXPECT_GT(c.mahalanobis2, 18.5);
      const double dt = r.filter.state(r.filter.nodes() - 1).dt_l + c.correction(Filter::kTime);
      EXPECT_NEAR(dt, offset, 4 * std::sqrt(c.covariance(Filter::kTime, Filter::kTime)) + 2e-4);
    }
  }
}

TEST(DopplerInertialFilter, NodesPolynomialsFromIncrementsAreTheIntegrations) {
  // Each node's integrations to its fit instants are increments made once at biases on a grid
  // (here zero: the cells are 0.4 rad/s and 4 m/s^2 wide at 2.5 ms) and applied at the state's
  // to first order. At the smoothed states (biases ~0.005 off the grid) the polynomials give the
  // exact integration's LiDAR velocity at the instants within 1e-8 m/s: the second order's
  // error is ~1e-10; a first-order term left out or of the wrong sign would leave ~1e-5.
  const test::AnalyticMotion m;
  const Noise noise{0.002, 0.02, 0.03};
  const OffsetWindow w = offsetWindow(m, noise, 0.0, 31);
  const std::vector<ImuSample>& imu = w.imu;
  const WindowRun r = runWindow(m, imu, w.ret, noise, 75);
  const Filter& f = r.filter;
  const double half = 0.5 / kImuRate;
  double worst = 0;
  for (std::size_t k = 1; k + 1 < f.nodes(); ++k) {
    const Filter::Vec9 Q = f.lidarVelocityPolynomial(k);
    for (double tau : {-half, 0.0, half}) {
      const double s = f.normalizedTime(k, tau);
      const Vec3 q = Q.segment<3>(0) + s * Q.segment<3>(3) + s * s * Q.segment<3>(6);
      const Vec3 exact = f.lidarVelocity(f.state(k), imu, f.nodeSample(k), tau);
      worst = std::max(worst, (q - exact).norm());
    }
  }
  EXPECT_LT(worst, 1e-8);
  EXPECT_GT(f.state(f.nodes() - 1).b_g.norm(), 1e-3);  // the biases are off the grid's point
}

TEST(DopplerInertialFilter, CalibrationTestMadeAheadIsContinuedByTheClosingOne) {
  // The pipeline makes the calibration test's pass over the nodes of its early smoothing right
  // after it, around the states it left, and the closing call continues it over the last
  // quarter. Against the test made whole at the end, around the final linearization (the two
  // differ by the final smoothing's steps): the same verdict, the statistic within 1 %, the
  // correction within a tenth of its std where the clocks agree; with the 4 ms offset, a
  // correction 9 std from where both linearize, within a quarter (measured: the offset 3.85 and
  // 3.82 ms, the rotation 0.18 std apart). Where a node before the kept ones' end changes (a
  // return taken back), the kept pass goes and the test is the whole one, to the bit.
  const test::AnalyticMotion m;
  const Noise noise{0.002, 0.02, 0.03};
  for (double offset : {0.0, 0.004}) {
    const OffsetWindow w = offsetWindow(m, noise, offset);
    const std::vector<ImuSample>& imu = w.imu;
    const Returns& ret = w.ret;
    auto earlyWith = [](bool ahead_test) {
      return [ahead_test](Filter& f, std::size_t k) {
        if (k != 75) return;
        f.smooth(1.0, true);
        if (ahead_test) f.testCalibrationAhead(kDeg, 0.01);
      };
    };
    const WindowRun whole = runWindow(m, imu, ret, noise, 0, true, earlyWith(false));
    const WindowRun ahead = runWindow(m, imu, ret, noise, 0, true, earlyWith(true));
    const Filter::CalibrationTest a = whole.filter.testCalibration(kDeg, 0.01);
    const Filter::CalibrationTest b = ahead.filter.testCalibration(kDeg, 0.01);
    ASSERT_TRUE(a.ok && b.ok);
    EXPECT_EQ(a.mahalanobis2 > 18.5, b.mahalanobis2 > 18.5) << "offset " << offset;
    EXPECT_NEAR(b.mahalanobis2, a.mahalanobis2, 0.01 * a.mahalanobis2) << "offset " << offset;
    EXPECT_NE(a.mahalanobis2, b.mahalanobis2) << "the kept pass was not used";
    const double within = offset == 0 ? 0.1 : 0.25;
    for (int i : {int(Filter::kRot), Filter::kRot + 1, Filter::kRot + 2, int(Filter::kTime)})
      EXPECT_LT(std::abs(a.correction(i) - b.correction(i)), within * std::sqrt(a.covariance(i, i)))
          << "offset " << offset << " component " << i;
    // A return of node 10 taken back after the pass was kept: the whole test, to the bit.
    Filter changed = ahead.filter;
    changed.removePoint(10, 0.0, ret.p_l[0], 0.0);
    changed.smooth();
    Filter fresh = whole.filter;
    fresh.removePoint(10, 0.0, ret.p_l[0], 0.0);
    fresh.smooth();
    const Filter::CalibrationTest c = changed.testCalibration(kDeg, 0.01);
    const Filter::CalibrationTest d = fresh.testCalibration(kDeg, 0.01);
    EXPECT_EQ(c.mahalanobis2, d.mahalanobis2);
    EXPECT_TRUE(c.correction == d.correction);
  }
}

TEST(DopplerInertialFilter, EstimatesTheTimeOffsetInItsState) {
  // The window of the test above, the LiDAR clock 4 ms ahead, with the offset in the state (prior
  // std 10 ms): the filter and smoother on the first 16 components (the rotation exact) recover
  // it, as they do on all 19 with the rotation free but held by a tiny prior.
  const test::AnalyticMotion m;
  const Noise noise{0.002, 0.02, 0.03};
  std::mt19937 rng(21);
  const auto imu = imuOf(m, 0.6, noise, rng);
  const Returns ret = returnsOf(m, 0.5, 20000, noise.doppler, 0.004, rng);
  const WindowRun time_only = runWindow(m, imu, ret, noise, 0, true, {}, 0.01, 0.0);
  const WindowRun all = runWindow(m, imu, ret, noise, 0, true, {}, 0.01, 1e-9);
  const Filter& f = time_only.filter;
  const double dt = f.state(f.nodes() - 1).dt_l;
  const double sigma = std::sqrt(f.covariance()(Filter::kTime, Filter::kTime));
  EXPECT_LT(sigma, 0.002);
  EXPECT_NEAR(dt, 0.004, 4 * sigma + 2e-4);
  const Filter& g = all.filter;
  EXPECT_NEAR(g.state(g.nodes() - 1).dt_l, dt, 0.05 * sigma);
  EXPECT_NEAR(std::sqrt(g.covariance()(Filter::kTime, Filter::kTime)), sigma, 0.01 * sigma);
  EXPECT_LT((g.state(g.nodes() - 1).v_w - f.state(f.nodes() - 1).v_w).norm(), 1e-4);
}

}  // namespace
}  // namespace freeinit
