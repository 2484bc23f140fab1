// The joint pipeline: start decision, then the Doppler-aided inertial filter over the window's
// nodes (one per IMU sample) as the data arrive, then the iterated smoother and the outputs.
//
// Parts, each with one job:
//   decideStart (start_detector.h)     what moves at the window start, and the first state
//   RestTracker (below)                whether the IMU still shows rest (zero-rate knowledge)
//   DopplerInertialFilter              the estimator proper
//   WindowRecorder (below)             the map points, the trajectory and the velocities
#include <freeinit/doppler_inertial_filter.h>
#include <freeinit/rotation.h>
#include <freeinit/start_detector.h>

#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>

#include "pipeline.h"
#include "velocimeter_steps.h"

namespace freeinit::detail {
namespace {

double wallSeconds() {
  using Clock = std::chrono::steady_clock;
  return std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
}

/// Whether the IMU still shows rest: each new sample is compared with the rest means of the
/// start span. One sample beyond 5 sigma, or the mean of the last four beyond 3 sigma (6 of the
/// mean's sigmas), in the gyro or the accelerometer, ends the rest for the rest of the window.
class RestTracker {
 public:
  void start(bool at_rest, const Vec3& gyro_mean, const Vec3& accel_mean, double gyro_sigma,
             double accel_sigma) {
    at_rest_ = at_rest;
    gyro_mean_ = gyro_mean;
    accel_mean_ = accel_mean;
    gyro_sigma_ = gyro_sigma;
    accel_sigma_ = accel_sigma;
    n_ = 0;
  }
  bool atRest() const { return at_rest_; }
  /// Feeds the next sample; returns atRest().
  bool update(const ImuSample& s) {
    if (!at_rest_) return false;
    const Vec3 dg = s.gyro - gyro_mean_, da = s.accel - accel_mean_;
    recent_g_[n_ % 4] = dg;
    recent_a_[n_ % 4] = da;
    ++n_;
    bool moving = dg.norm() > 5.0 * gyro_sigma_ || da.norm() > 5.0 * accel_sigma_;
    if (n_ >= 4) {
      const Vec3 mg = (recent_g_[0] + recent_g_[1] + recent_g_[2] + recent_g_[3]) / 4.0;
      const Vec3 ma = (recent_a_[0] + recent_a_[1] + recent_a_[2] + recent_a_[3]) / 4.0;
      moving = moving || mg.norm() > 3.0 * gyro_sigma_ || ma.norm() > 3.0 * accel_sigma_;
    }
    if (moving) at_rest_ = false;
    return at_rest_;
  }

 private:
  bool at_rest_ = false;
  Vec3 gyro_mean_ = Vec3::Zero(), accel_mean_ = Vec3::Zero();
  double gyro_sigma_ = 1, accel_sigma_ = 1;
  std::array<Vec3, 4> recent_g_{}, recent_a_{};
  std::size_t n_ = 0;
};

/// The points of the window in the body frame of their node, mapped into the world once the
/// node poses are final.
class WindowRecorder {
 public:
  void add(std::size_t node, const Eigen::Vector3f& x_b, float intensity, float residual,
           bool accepted) {
    (accepted ? accepted_ : rejected_).push_back({node, x_b, intensity, residual});
  }
  /// Maps every point with the final node states.
  void finish(const DopplerInertialFilter& filter, InitResult& r) const {
    auto map = [&](const std::vector<Point>& in, std::vector<MapPoint>& out) {
      out.clear();
      out.reserve(in.size());
      for (const Point& p : in) {
        const FilterState& x = filter.state(p.node);
        MapPoint m;
        m.p_w = (x.R_wb * p.x_b.cast<double>() + x.p_w).cast<float>();
        m.intensity = p.intensity;
        m.residual = p.residual;
        out.push_back(m);
      }
    };
    map(accepted_, r.static_map);
    map(rejected_, r.rejected);
  }

 private:
  struct Point {
    std::size_t node;
    Eigen::Vector3f x_b;
    float intensity;
    float residual;
  };
  std::vector<Point> accepted_, rejected_;
};

class JointPipeline final : public Pipeline {
 public:
  JointPipeline(const FreeInitConfig& cfg, const MeasurementSequencer& seq)
      : cfg_(cfg), seq_(seq) {}

  bool pump(InitResult& r) override {
    if (phase_ == Phase::Done) return true;
    const double t0 = wallSeconds();
    if (phase_ == Phase::WaitStart) tryStart(r);
    if (phase_ == Phase::Running) run(r);
    if (phase_ != Phase::Done) r.diag.time_velocimeter += wallSeconds() - t0;
    if (phase_ == Phase::Running && seq_.finished()) {
      std::ostringstream window;
      window << cfg_.window.duration;
      fail(r, InitStatus::NotEnoughData,
           "the recording ends before the initialization window (" + window.str() +
               " s) is covered");
    }
    if (phase_ == Phase::WaitStart && seq_.finished())
      fail(r, InitStatus::NotEnoughData, "no IMU sample overlaps the LiDAR data");
    return phase_ == Phase::Done;
  }

 private:
  enum class Phase { WaitStart, Running, Done };

  void fail(InitResult& r, InitStatus s, const std::string& msg) {
    failResult(r, s, msg);
    phase_ = Phase::Done;
  }

  DopplerInertialFilterParams filterParams() const {
    DopplerInertialFilterParams p;
    const VelocimeterParams& v = cfg_.velocimeter;
    p.doppler_sigma = v.doppler_sigma;
    p.gyro_sigma = v.gyro_sigma;
    p.accel_sigma = cfg_.gravity.accel_sigma;
    p.gyro_bias_random_walk = v.gyro_bias_random_walk;
    p.accel_bias_random_walk = cfg_.estimator.accel_bias_random_walk;
    p.gate_sigma = v.gate_sigma;
    p.gate_min = v.gate_min;
    p.gate_rel = v.gate_rel;
    p.max_iterations = cfg_.estimator.max_iterations;
    return p;
  }

  void tryStart(InitResult& r) {
    const VelocimeterParams& vp = cfg_.velocimeter;
    if (vp.doppler_ego_compensated) {
      fail(r, InitStatus::NoDoppler,
           "the Doppler values are ego-compensated: they carry no ego velocity; Free-Init needs "
           "the raw (range-rate) Doppler");
      return;
    }
    const auto& imu = seq_.imu();
    MeasurementSequencer::Cursor c;
    if (!seq_.normalize(c) || imu.empty()) return;
    // Window start: the first IMU sample at or after the first LiDAR point.
    const double tp0 = seq_.time(c);
    std::size_t k = 0;
    while (k < imu.size() && imu[k].t < tp0) ++k;
    if (k + 1 >= imu.size()) return;
    const double t_ref = imu[k].t;
    // The start decision's span: bootstrap_duration, within the window.
    const double span = std::min(cfg_.estimator.bootstrap_duration, cfg_.window.duration);
    std::size_t k1 = k;
    while (k1 + 1 < imu.size() && imu[k1].t < t_ref + span &&
           imu[k1 + 1].t - t_ref < cfg_.window.duration)
      ++k1;
    const bool span_complete = imu[k1].t >= t_ref + span ||
                               (k1 + 1 < imu.size() && imu[k1 + 1].t - t_ref >= cfg_.window.duration);
    if ((!span_complete || !seq_.lidarPassed(imu[k1].t)) && !seq_.finished()) return;
    if (k1 < k + 2) return;  // wait for a few samples at least (finished: not enough data)

    // Returns of the span, evenly thinned to bootstrap_points.
    const double t_end = imu[k1].t;
    std::size_t usable = 0;
    for (MeasurementSequencer::Cursor q = c; seq_.normalize(q) && seq_.time(q) <= t_end; ++q.p)
      if (seq_.time(q) >= t_ref && usablePoint(seq_.point(q), vp)) ++usable;
    const std::size_t thin =
        std::max<std::size_t>(1, usable / static_cast<std::size_t>(cfg_.estimator.bootstrap_points));
    std::vector<StartPoint> pts;
    pts.reserve(usable / thin + 1);
    std::size_t n = 0;
    for (MeasurementSequencer::Cursor q = c; seq_.normalize(q) && seq_.time(q) <= t_end; ++q.p) {
      const double t = seq_.time(q);
      const DopplerPoint& p = seq_.point(q);
      if (t < t_ref || !usablePoint(p, vp)) continue;
      if (n++ % thin != 0) continue;
      pts.push_back({t - t_ref, p.p_l.cast<double>().normalized(), p.doppler});
    }
    StartDetectorParams sp;
    sp.doppler_sigma = vp.doppler_sigma;
    sp.gyro_sigma = vp.gyro_sigma;
    sp.accel_sigma = cfg_.gravity.accel_sigma;
    sp.gyro_bias_sigma = vp.gyro_bias_sigma0;
    sp.gate = vp.gate_min;
    sp.max_speed = cfg_.static_detector.max_speed;
    sp.min_info_eigen = cfg_.bootstrap.min_info_eigen;
    const StartDecision d =
        decideStart(imu, k, k1, pts, cfg_.extrinsics, vp.gyro_bias_prior, sp);
    r.diag.imu_at_rest_at_start = d.imu_still;
    switch (d.kind) {
      case StartDecision::Kind::NoData: fail(r, InitStatus::NoDoppler, d.message); return;
      case StartDecision::Kind::Degenerate:
        fail(r, InitStatus::DegenerateGeometry, "start: " + d.message);
        return;
      case StartDecision::Kind::Ambiguous:
        fail(r, InitStatus::AmbiguousMotion, d.message);
        return;
      case StartDecision::Kind::Moving:
      case StartDecision::Kind::Rest: break;
    }
    k0_ = k;
    t_ref_ = t_ref;
    stride_ = vp.point_stride > 0 ? vp.point_stride : automaticPointStride(frameList(), vp.max_point_rate);
    startFilter(d);
    Vec3 gm = Vec3::Zero(), am = Vec3::Zero();
    for (std::size_t i = k; i <= k1; ++i) {
      gm += imu[i].gyro;
      am += imu[i].accel;
    }
    const double cnt = static_cast<double>(k1 - k + 1);
    const bool rest = d.kind == StartDecision::Kind::Rest && d.imu_still &&
                      cfg_.static_detector.enabled;
    rest_.start(rest, gm / cnt, am / cnt, vp.gyro_sigma, cfg_.gravity.accel_sigma);
    r.diag.static_start = d.kind == StartDecision::Kind::Rest && cfg_.static_detector.enabled;
    cursor_ = c;
    node_open_ = false;
    phase_ = Phase::Running;
  }

  /// Frames as the automatic stride wants them (anything with a `points` vector).
  struct FramePoints {
    const std::vector<DopplerPoint>& points;
  };
  std::vector<FramePoints> frameList() const {
    std::vector<FramePoints> out;
    for (const auto& f : seq_.frames()) out.push_back({*f.points});
    return out;
  }

  /// The filter's first node: attitude from the decision's gravity (yaw zero: the world's
  /// gauge), velocity from its v_b0; covariance: tilt uninformative (initial_tilt_sigma), the body
  /// velocity from the decision (inflated: the filter sees those returns again), the bias priors.
  void startFilter(const StartDecision& d) {
    const Mat3 R0 = alignToGravity(d.chosen.g_b0);
    FilterState x0;
    x0.R_wb = R0;
    x0.v_w = R0 * d.chosen.v_b0;
    x0.b_g = cfg_.velocimeter.gyro_bias_prior;
    x0.b_a = Vec3::Zero();
    using Mat6 = Eigen::Matrix<double, 6, 6>;
    Mat6 C = Mat6::Zero();  // (dtheta, dv_b)
    Mat3 tilt_w = Mat3::Zero();
    const double st = cfg_.estimator.initial_tilt_sigma;
    tilt_w(0, 0) = tilt_w(1, 1) = st * st;
    tilt_w(2, 2) = 1e-12;  // yaw: the gauge
    C.topLeftCorner<3, 3>() = R0.transpose() * tilt_w * R0;
    constexpr double kInflation = 9.0;  // variance factor: the filter counts those returns again
    C.bottomRightCorner<3, 3>() = d.chosen.cov.topLeftCorner<3, 3>() * kInflation;
    // v_w = R v_b: dv_w = R dv_b - R [v_b]x dtheta, so that a tilt change alone keeps v_b.
    Mat6 K = Mat6::Identity();
    K.block<3, 3>(3, 0) = -R0 * skew(d.chosen.v_b0);
    K.block<3, 3>(3, 3) = R0;
    const Mat6 Cw = K * C * K.transpose();
    DopplerInertialFilter::Mat15 P0 = DopplerInertialFilter::Mat15::Zero();
    P0.block<3, 3>(0, 0) = Cw.block<3, 3>(0, 0);
    P0.block<3, 3>(0, 6) = Cw.block<3, 3>(0, 3);
    P0.block<3, 3>(6, 0) = Cw.block<3, 3>(3, 0);
    P0.block<3, 3>(6, 6) = Cw.block<3, 3>(3, 3);
    P0.block<3, 3>(3, 3).diagonal().setConstant(1e-12);  // the origin: the gauge
    const double sg = cfg_.velocimeter.gyro_bias_sigma0;
    const double sa = cfg_.gravity.accel_bias_prior_sigma;
    P0.block<3, 3>(9, 9).diagonal().setConstant(sg * sg);
    P0.block<3, 3>(12, 12).diagonal().setConstant(sa * sa);
    // Node 0 is gated with the decision's own (not inflated) velocity covariance.
    DopplerInertialFilter::Mat15 P_gate = P0;
    P_gate.block<3, 3>(6, 6) /= kInflation;
    filter_.emplace(filterParams(), cfg_.extrinsics);
    filter_->start(seq_.imu()[k0_], x0, P0, &P_gate);
  }

  void run(InitResult& r) {
    const auto& imu = seq_.imu();
    const VelocimeterParams& vp = cfg_.velocimeter;
    while (true) {
      const std::size_t k = k0_ + filter_->nodes() - 1;
      if (!node_open_) {
        // The window rule (config.h): this sample closes the window, or the next one is beyond.
        const double duration = cfg_.window.duration;
        last_ = k > k0_ && windowSample(imu[k0_].t, imu[k - 1].t, imu[k].t, duration) ==
                               WindowSample::Last;
        if (!last_) {
          if (k + 1 >= imu.size()) return;  // the node's interval needs the next sample
          last_ = windowSample(imu[k0_].t, imu[k].t, imu[k + 1].t, duration) ==
                  WindowSample::Outside;
        }
        if (last_) k_end_ = k;
        filter_->beginNode(last_ ? nullptr : &imu[k + 1]);
        node_open_ = true;
      }
      const bool last = last_;
      const double t_k = imu[k].t;
      const double lo = t_k - filter_->intervalBefore();
      const double hi = t_k + filter_->intervalAfter();
      // The node's points.
      while (seq_.normalize(cursor_)) {
        const double t = seq_.time(cursor_);
        if (last ? t > t_k : t >= hi) break;
        const DopplerPoint& pt = seq_.point(cursor_);
        ++cursor_.p;
        if (t < lo) continue;  // before the window
        ++r.diag.points_seen;
        const bool use = stride_counter_ == 0;
        if (++stride_counter_ == static_cast<std::size_t>(stride_)) stride_counter_ = 0;
        if (!use || !usablePoint(pt, vp)) {
          ++r.diag.points_skipped;
          continue;
        }
        const auto out = filter_->addPoint(t - t_k, pt.p_l, pt.doppler);
        (out.accepted ? r.diag.points_used : r.diag.points_rejected)++;
        recorder_.add(filter_->nodes() - 1, out.x_b, pt.intensity,
                      static_cast<float>(out.residual), out.accepted);
      }
      if (!seq_.lidarPassed(last ? t_k + 1e-9 : hi)) return;  // more points may come
      filter_->update();
      const bool rest = rest_.update(imu[k]);
      if (rest)
        filter_->updateRest(cfg_.estimator.rest_velocity_sigma,
                            cfg_.estimator.zero_rate_at_rest ? vp.gyro_sigma : 0.0);
      if (rest) r.diag.static_duration = t_k - t_ref_;
      node_rest_.push_back(rest);
      ++r.diag.gyro_updates;
      node_open_ = false;
      if (last) {
        finalize(r);
        return;
      }
      filter_->predict(imu[k + 1]);
    }
  }

  void finalize(InitResult& r) {
    phase_ = Phase::Done;
    const double t_solve = wallSeconds();
    Diagnostics& diag = r.diag;
    const auto& imu = seq_.imu();
    const double T = imu[k_end_].t - t_ref_;
    diag.window_duration = T;
    diag.update_rate_hz = T > 0 ? static_cast<double>(diag.points_used + diag.gyro_updates) / T : 0;
    for (const auto& f : seq_.frames()) {
      if (f.points->empty()) continue;
      const double a = f.stamp + static_cast<double>(f.points->front().time_offset);
      const double b = f.stamp + static_cast<double>(f.points->back().time_offset);
      if (b >= t_ref_ && a <= imu[k_end_].t) ++diag.frames_in_window;
    }
    if (diag.points_used < 10 && !diag.static_start) {
      fail(r, InitStatus::NoDoppler, "no Doppler return passed the gate in the window");
      return;
    }
    diag.iterations = filter_->smooth();
    diag.time_solver = wallSeconds() - t_solve;
    const std::size_t N = filter_->nodes();
    const FilterState& x = filter_->state(N - 1);
    const std::size_t used = filter_->acceptedPointsTotal();
    diag.doppler_residual_rms =
        used > 0 ? std::sqrt(filter_->residualSumOfSquares() / static_cast<double>(used)) : 0.0;
    std::ostringstream rep;
    rep << "joint: " << N << " nodes, " << diag.iterations << " smoother iterations";
    diag.solver_report = rep.str();

    InitialState& s = r.state;
    s.status = InitStatus::Ok;
    s.message.clear();
    s.timestamp = x.t;
    s.q_wb = Quat(x.R_wb).normalized();
    s.p_w = x.p_w;
    s.v_w = x.v_w;
    s.b_g = x.b_g;
    s.b_a = x.b_a;
    s.g_w = Vec3(0, 0, -kGravity);
    s.cov.setZero();
    s.cov.topLeftCorner<15, 15>() = filter_->covariance();
    s.cov.block<3, 3>(kGrav, kGrav).diagonal().setConstant(1e-6);  // fixed by the world frame
    s.cov = 0.5 * (s.cov + s.cov.transpose()).eval();

    // Trajectory and velocities at every node; the map with the final node poses.
    r.trajectory.clear();
    r.velocities.clear();
    for (std::size_t k = 0; k < N; ++k) {
      const FilterState& xk = filter_->state(k);
      const ImuSample& sk = imu[k0_ + k];
      PoseSample p;
      p.t = sk.t;
      p.q_wb = Quat(xk.R_wb).normalized();
      p.p_w = xk.p_w;
      r.trajectory.push_back(p);
      VelocitySample v;
      v.t = sk.t;
      v.v_b = xk.R_wb.transpose() * xk.v_w;
      v.omega_b = sk.gyro - xk.b_g;
      v.v_l = cfg_.extrinsics.R_bl.transpose() * (v.v_b + v.omega_b.cross(cfg_.extrinsics.p_bl));
      v.b_g = xk.b_g;
      v.stationary = k < node_rest_.size() && node_rest_[k];
      r.velocities.push_back(v);
    }
    // The last node's velocity sigma from the state covariance (dv_b = R^T dv_w + [v_b]x dtheta).
    {
      Eigen::Matrix<double, 3, 15> A = Eigen::Matrix<double, 3, 15>::Zero();
      const Vec3 v_b = x.R_wb.transpose() * x.v_w;
      A.block<3, 3>(0, 0) = skew(v_b);
      A.block<3, 3>(0, 6) = x.R_wb.transpose();
      r.velocities.back().sigma_v_b =
          (A * filter_->covariance() * A.transpose()).diagonal().cwiseSqrt();
    }
    recorder_.finish(*filter_, r);
    addWarnings(r);
  }

  /// What a user must know about an ok state; a gross inconsistency is not reported as a state.
  void addWarnings(InitResult& r) {
    InitialState& s = r.state;
    const Diagnostics& d = r.diag;
    auto fmt = [](double v, int prec = 3) {
      std::ostringstream os;
      os.precision(prec);
      os << v;
      return os.str();
    };
    const double sigma = cfg_.velocimeter.doppler_sigma;
    if (d.points_used >= 100 && d.doppler_residual_rms > 1.5 * sigma) {
      s.warnings.push_back("the Doppler residuals (RMS " + fmt(d.doppler_residual_rms) +
                           " m/s) exceed the configured Doppler noise (" + fmt(sigma) +
                           " m/s): the noise setting, the extrinsics or the LiDAR-IMU time "
                           "offset may be wrong");
    }
    const std::size_t judged = d.points_used + d.points_rejected;
    if (judged >= 100 && d.points_used < 0.3 * static_cast<double>(judged)) {
      s.warnings.push_back("only " + fmt(100.0 * d.points_used / judged, 2) +
                           " % of the LiDAR returns in the window agree with the estimated "
                           "motion (moving objects, outliers or a wrong calibration)");
    }
    const double bound = cfg_.gravity.accel_bias_bound;
    const double ba_max = s.b_a.cwiseAbs().maxCoeff();
    if (ba_max > 3.0 * bound) {
      failResult(r, InitStatus::InconsistentData,
                 "the accelerometer bias the data imply (" + fmt(ba_max) +
                     " m/s^2 on one axis) is far beyond its plausible bound (" + fmt(bound) +
                     " m/s^2): the IMU model, the extrinsics or the time offset is wrong");
      return;
    }
    if (ba_max > bound)
      s.warnings.push_back("the accelerometer bias (" + fmt(ba_max) +
                           " m/s^2 on one axis) exceeds its plausible bound (" + fmt(bound) +
                           " m/s^2)");
    const Vec3 dbg = s.b_g - cfg_.velocimeter.gyro_bias_prior;
    const double sg0 = cfg_.velocimeter.gyro_bias_sigma0;
    if (dbg.cwiseAbs().maxCoeff() > 4.0 * sg0)
      s.warnings.push_back("the gyro bias moved " + fmt(dbg.cwiseAbs().maxCoeff()) +
                           " rad/s from its prior, more than 4 prior sigmas (" + fmt(sg0) +
                           " rad/s)");
  }

  const FreeInitConfig& cfg_;
  const MeasurementSequencer& seq_;
  Phase phase_ = Phase::WaitStart;
  std::size_t k0_ = 0, k_end_ = 0;
  double t_ref_ = 0;
  int stride_ = 1;
  std::size_t stride_counter_ = 0;
  MeasurementSequencer::Cursor cursor_;
  bool node_open_ = false;
  bool last_ = false;  ///< the open node is the window's last
  std::optional<DopplerInertialFilter> filter_;
  RestTracker rest_;
  std::vector<bool> node_rest_;
  WindowRecorder recorder_;
};

}  // namespace

std::unique_ptr<Pipeline> makeJointPipeline(const FreeInitConfig& config,
                                            const MeasurementSequencer& sequencer) {
  return std::make_unique<JointPipeline>(config, sequencer);
}

}  // namespace freeinit::detail
