// The joint pipeline: start decision, then the Doppler-aided inertial filter over the window's
// nodes (one per IMU sample, or at every m-th sample with [joint] node_rate, the window's last
// sample always a node) as the data arrive, then the iterated smoother and the outputs.
//
// Parts, each with one job:
//   decideStart (start_detector.h)     what moves at the window start, and the first state
//   RestTracker (window_parts.h)       whether the IMU still shows rest (zero-rate knowledge)
//   DopplerInertialFilter              the estimator proper
//   WindowRecorder (window_parts.h)    the window's returns as received, mapped at the end
//   RestCells (window_parts.h)         a standing sensor's returns by direction and range
#include <freeinit/input_checks.h>
#include <freeinit/io/number_format.h>
#include <freeinit/rotation.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <sstream>
#include <utility>

#include "imu_screen.h"
#include "joint/chi_square.h"
#include "joint/doppler_inertial_filter.h"
#include "joint/noise_estimate.h"
#include "joint/start_detector.h"
#include "joint/window_parts.h"
#include "pipeline.h"
#include "usable_points.h"

namespace freeinit::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;
/// [s] how long before the IMU shows it a motion may have begun (a gentle start): the rest
/// knowledge of those last nodes is taken back.
constexpr double kRestBackdating = 0.1;
/// Share of the window after which what has been received is smoothed once. Three quarters, so
/// that at 10 Hz or faster the node it ends with lies in a frame before the one that closes the
/// window, whatever the window's phase against the frames: a stream then runs it in an earlier
/// call than the one a user waits for (at 80 %, a window starting with a frame at 10 Hz had it
/// in the closing call: node at 0.4 s, its interval to 0.4025 s, the last frame from 0.4 s). At
/// 5 Hz it still is in 9 of 20 phases (12 at 80 %).
constexpr double kEarlySmoothing = 0.75;
/// That early smoothing is the final one's starting point, not a result: it stops once its next
/// step would be below this many times the final one's threshold (DopplerInertialFilter::smooth).
/// Held-out seeds 17000001-200 and 18000001-200: 13 % and 10 % fewer early iterations, 2 % fewer
/// final ones, no status change; 90 % of the states the same to 1e-4 of their bound, all within
/// 0.04 of it but in the runs confidently wrong either way (their answers depend on the path).
constexpr double kEarlyLooseness = 100.0;
/// Returns below which the Doppler noise is not read from their residuals (the configured one is
/// used).
constexpr std::size_t kMinNoiseReturns = 100;

/// The screen's settings. The configured noises floor its tests and are the white part of its
/// replacements' error; the variance it hands the filter is absolute (ImuExtraNoise), added to
/// whichever noise the filter uses.
ImuScreenParams screenParams(const FreeInitConfig& cfg) {
  ImuScreenParams p;
  p.gyro_range = cfg.imu.gyro_range;
  p.accel_range = cfg.imu.accel_range;
  p.fault_sigmas = cfg.imu.fault_sigmas;
  p.gyro_sigma = cfg.imu.gyro_sigma;
  p.accel_sigma = cfg.imu.accel_sigma;
  p.max_bridged_gap = cfg.imu.max_bridged_gap;
  return p;
}

/// The covariance of the body velocity v_b = R^T v_w at x given P, the filter's error state's:
/// A P A^T with A = dv_b/ddx = [[v_b]x (attitude), R^T (velocity), 0 elsewhere], from those two
/// blocks (the 3 x 19 product went through Eigen's general matrix product: 0.08 ms per window).
Mat3 bodyVelocityCovariance(const FilterState& x, const DopplerInertialFilter::MatS& P) {
  using F = DopplerInertialFilter;
  const Mat3 Rt = x.R_wb.transpose();
  const Mat3 S = skew(Rt * x.v_w);
  const Mat3 cross = S * P.block<3, 3>(F::kTheta, F::kVel) * Rt.transpose();
  return S * P.block<3, 3>(F::kTheta, F::kTheta) * S.transpose() + cross + cross.transpose() +
         Rt * P.block<3, 3>(F::kVel, F::kVel) * Rt.transpose();
}

class JointPipeline final : public Pipeline {
 public:
  JointPipeline(const FreeInitConfig& cfg, const MeasurementSequencer& seq)
      : cfg_(cfg), seq_(seq), usable_(cfg.doppler), screen_(screenParams(cfg)) {}

  bool processBuffered(InitResult& r) override {
    if (phase_ == Phase::Done) return true;
    // Everything below reads the screened IMU stream (faults replaced, short gaps bridged).
    screen_.advance(seq_.imu(), seq_.finished());
    const double t0 = wallSeconds(), solver0 = r.diag.time_solver;
    if (phase_ == Phase::WaitStart) tryStart(r);
    if (phase_ == Phase::Running) run(r);
    r.diag.time_velocimeter += wallSeconds() - t0 - (r.diag.time_solver - solver0);
    if (phase_ == Phase::Running && seq_.finished()) {
      // The open node's returns were counted as seen; those not usable count as skipped.
      r.diag.points_skipped += recorder_.openUnusable(usable_);
      std::ostringstream window;
      window << cfg_.window.duration;
      fail(r, InitStatus::NotEnoughData,
           "the recording ends before the initialization window (" + window.str() +
               " s) is covered");
    }
    if (phase_ == Phase::WaitStart && seq_.finished())
      fail(r, InitStatus::NotEnoughData, noWindowReason(seq_));
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
    const DopplerParams& d = cfg_.doppler;
    const ImuParams& imu = cfg_.imu;
    p.doppler_sigma = d.doppler_sigma;
    p.gyro_sigma = imu.gyro_sigma;
    p.accel_sigma = imu.accel_sigma;
    p.gyro_bias_random_walk = imu.gyro_bias_random_walk;
    p.accel_bias_random_walk = imu.accel_bias_random_walk;
    p.gate_sigma = d.gate_sigma;
    p.gate_min = d.gate_min;
    p.gate_rel = d.gate_rel;
    p.max_iterations = cfg_.joint.max_iterations;
    p.lever_arm_gyro_noise = cfg_.joint.lever_arm_gyro_noise;
    return p;
  }

  void tryStart(InitResult& r) {
    const DopplerParams& dp = cfg_.doppler;
    if (dp.doppler_ego_compensated) {
      fail(r, InitStatus::NoDoppler,
           "the Doppler values are ego-compensated: they carry no ego velocity; Free-Init needs "
           "the raw (range-rate) Doppler");
      return;
    }
    const auto& imu = screen_.samples();
    MeasurementSequencer::Cursor c;
    if (!seq_.normalize(c) || imu.empty()) return;
    // Window start: the first IMU sample at or after the first LiDAR point; the start
    // decision's span: [start] duration, within the window.
    const StartSpan start = startSpan(imu, seq_.time(c), cfg_);
    if (!start.valid) return;
    const std::size_t k = start.k_first, k_last = start.k_last;
    const double t_ref = imu[k].t;
    if ((!start.complete || !seq_.lidarPassed(imu[k_last].t)) && !seq_.finished()) return;
    if (k_last < k + 2) return;  // wait for a few samples at least (finished: not enough data)
    // The decision interpolates the IMU with the two samples after the span: wait for them, so
    // that it does not depend on how far the IMU stream happens to be ahead.
    if (k_last + 2 >= imu.size() && !seq_.finished()) return;

    // Returns of the span, evenly thinned to [start] points: the usable ones (in time order,
    // up to the first return after the span), then every thin-th. A frame's times do not
    // decrease (the sequencer checks it): its part of the span is found by bisection, and the
    // verdicts on that part come from the recorder's vectorized layout, a block at a time.
    const double t_end = imu[k_last].t;
    struct FramePart {
      std::size_t f, begin, end;
    };
    std::vector<FramePart> parts;
    std::size_t span_returns = 0;
    const auto& frames = seq_.frames();
    for (std::size_t f = c.f; f < frames.size(); ++f) {
      const DopplerPoint* fp = frames[f].points->data();
      const std::size_t n = frames[f].points->size();
      const double stamp = frames[f].stamp;
      auto time = [stamp](const DopplerPoint& q) {
        return stamp + static_cast<double>(q.time_offset);
      };
      const DopplerPoint* first = fp + (f == c.f ? c.p : 0);
      const DopplerPoint* end = std::partition_point(
          first, fp + n, [&](const DopplerPoint& q) { return !(time(q) > t_end); });
      const DopplerPoint* begin =
          std::partition_point(first, end, [&](const DopplerPoint& q) { return time(q) < t_ref; });
      parts.push_back(
          {f, static_cast<std::size_t>(begin - fp), static_cast<std::size_t>(end - fp)});
      span_returns += static_cast<std::size_t>(end - begin);
      if (end < fp + n) break;
    }
    struct SpanReturn {
      const DopplerPoint* p;
      double t;
    };
    std::vector<SpanReturn> usable;
    usable.reserve(span_returns);
    constexpr std::size_t kBlock = 1024;
    std::vector<float> block(6 * kBlock);
    std::vector<std::uint8_t> verdict(kBlock);
    float* a = block.data();
    for (const FramePart& part : parts) {
      const DopplerPoint* fp = frames[part.f].points->data();
      const double stamp = frames[part.f].stamp;
      for (std::size_t b = part.begin; b < part.end; b += kBlock) {
        const std::size_t m = std::min(kBlock, part.end - b);
        recorder_kernels::layOut(fp + b, m, 1, stamp, t_ref, usable_, a, a + kBlock, a + 2 * kBlock,
                                 a + 3 * kBlock, a + 4 * kBlock, a + 5 * kBlock, verdict.data());
        for (std::size_t i = 0; i < m; ++i)
          if (verdict[i] != 0)
            usable.push_back({fp + b + i, stamp + static_cast<double>(fp[b + i].time_offset)});
      }
    }
    const std::size_t thin =
        std::max<std::size_t>(1, usable.size() / static_cast<std::size_t>(cfg_.start.points));
    std::vector<StartPoint> pts;
    pts.reserve(usable.size() / thin + 1);
    for (std::size_t i = 0; i < usable.size(); i += thin) {
      const DopplerPoint& p = *usable[i].p;
      const Vec3 p_l = p.p_l.cast<double>();
      pts.push_back({usable[i].t - t_ref, p_l.normalized(), p.doppler, p_l.norm()});
    }
    const StartDecision d =
        decideStart(imu, k, k_last, pts, cfg_.extrinsics, cfg_.imu.gyro_bias_prior,
                    startDetectorParams(cfg_), &screen_.extraNoise());
    r.diag.imu_at_rest_at_start = d.imu_still;
    switch (d.kind) {
      case StartDecision::Kind::NoData:
        fail(r, InitStatus::NoDoppler, d.message);
        return;
      case StartDecision::Kind::Degenerate:
        fail(r, InitStatus::DegenerateGeometry, "start: " + d.message);
        return;
      case StartDecision::Kind::Ambiguous:
        fail(r, InitStatus::AmbiguousMotion, d.message);
        return;
      case StartDecision::Kind::Moving:
      case StartDecision::Kind::Rest:
        break;
    }
    k_first_ = k;
    t_ref_ = t_ref;
    stride_ = dp.point_stride > 0 ? dp.point_stride : automaticPointStride(seq_, dp.max_point_rate);
    reserveRecorder();
    Vec3 gm = Vec3::Zero(), am = Vec3::Zero();
    for (std::size_t i = k; i <= k_last; ++i) {
      gm += imu[i].gyro;
      am += imu[i].accel;
    }
    const double cnt = static_cast<double>(k_last - k + 1);
    const bool rest = d.kind == StartDecision::Kind::Rest && d.imu_still && cfg_.start.detect_rest;
    rest_.start(rest, gm / cnt, am / cnt, d.imu_rest.gyro, d.imu_rest.accel, cfg_.imu.gyro_sigma,
                cfg_.imu.accel_sigma);
    imu_noise_from_rest_ = rest;
    gyro_motion_ = accel_motion_ = NoisePosterior{};
    startDopplerNoise(d.chosen);
    startFilter(d);
    r.diag.static_start = d.kind == StartDecision::Kind::Rest && cfg_.start.detect_rest;
    cursor_ = c;
    node_open_ = false;
    phase_ = Phase::Running;
  }

  /// Room in the recorder for the window's returns at the rate of the frames received so far
  /// (their points over their stamps' span), after the stride: no re-allocation of the largest
  /// buffer while the window is received.
  void reserveRecorder() {
    const auto& frames = seq_.frames();
    std::size_t points = 0;
    for (std::size_t i = 0; i + 1 < frames.size(); ++i) points += frames[i].points->size();
    const double span = frames.size() >= 2 ? frames.back().stamp - frames.front().stamp : 0.0;
    if (!(span > 0)) return;
    const double expected = static_cast<double>(points) / span * cfg_.window.duration / stride_;
    // Frames stamped closer than their rate would suggest must not reserve without bound: the
    // buffer grows as needed beyond this.
    constexpr double kMostReserved = 4e6;
    const double reserved = std::min(1.05 * expected, kMostReserved);
    // In front, 2 % of that (two nodes' returns where the window has 100 nodes): room for the
    // map to be written behind the node it is read from, without copying the node aside.
    recorder_.reserve(static_cast<std::size_t>(reserved) + 1024,
                      static_cast<std::size_t>(0.02 * reserved));
  }

  /// The filter's first node: attitude from the decision's gravity (yaw zero: the world's
  /// gauge), velocity from its v_b0; covariance: tilt uninformative (initial_tilt_sigma), the body
  /// velocity from the decision (inflated: the filter sees those returns again), the bias priors.
  void startFilter(const StartDecision& d) {
    const Mat3 R0 = alignToGravity(d.chosen.g_b0);
    FilterState x0;
    x0.R_wb = R0;
    x0.v_w = R0 * d.chosen.v_b0;
    x0.b_g = cfg_.imu.gyro_bias_prior;
    x0.b_a = Vec3::Zero();
    x0.dt_l = d.chosen.time_offset;
    DopplerInertialFilter::StartPrior prior;
    prior.tilt_sigma = cfg_.joint.initial_tilt_sigma;
    constexpr double kInflation = 9.0;  // variance factor: the filter counts those returns again
    prior.cov_v_b = d.chosen.cov.topLeftCorner<3, 3>() * kInflation;
    prior.gate_velocity_scale = 1.0 / kInflation;
    prior.gyro_bias_sigma = cfg_.imu.gyro_bias_sigma0;
    prior.accel_bias_sigma = cfg_.imu.accel_bias_prior_sigma;
    prior.rotation_sigma = cfg_.joint.calibration_rotation_sigma_deg * kPi / 180.0;
    prior.time_sigma = cfg_.joint.time_offset_sigma;
    // The clock offset the start decision fitted with its motion: the filter's prior about it,
    // its std inflated as the velocity's (the filter sees those returns again), within the
    // configured one.
    if (d.chosen.time_offset_sigma > 0)
      prior.time_sigma = std::min(prior.time_sigma, 3.0 * d.chosen.time_offset_sigma);
    DopplerInertialFilterParams fp = filterParams();
    if (imu_noise_from_rest_) {  // the start span's noise at rest
      fp.gyro_sigma = rest_.gyroNoise().sigma;
      fp.accel_sigma = rest_.accelNoise().sigma;
    }
    if (doppler_noise_.sigma > 0) fp.doppler_sigma = doppler_noise_.sigma;
    filter_.emplace(fp, cfg_.extrinsics);
    // The window's nodes at the IMU rate of the start span over the node stride (a few more if
    // the rate varies: the nodes then grow as needed).
    const auto& imu = screen_.samples();
    node_stride_ = 1;
    const double h_imu = screen_.interval();
    if (cfg_.joint.node_rate > 0 && h_imu > 0)
      node_stride_ =
          static_cast<std::size_t>(std::max(1.0, std::round(1.0 / (h_imu * cfg_.joint.node_rate))));
    const std::size_t k_last = std::min(imu.size() - 1, k_first_ + 10);
    if (k_last > k_first_) {
      const double dt = static_cast<double>(node_stride_) * (imu[k_last].t - imu[k_first_].t) /
                        static_cast<double>(k_last - k_first_);
      constexpr double kMostNodes = 1e5;
      const std::size_t nodes =
          static_cast<std::size_t>(std::min(kMostNodes, 1.1 * cfg_.window.duration / dt)) + 4;
      filter_->reserveNodes(nodes);
      filter_->prepareSmoothing(nodes);
    }
    prepareMovingCellSums();
    fed_ = k_first_;
    feedImu(k_first_ + 2);
    filter_->start(x0, prior);
  }

  /// Hands the filter the IMU samples up to index `last` (the sequencer's) it has not seen. The
  /// filter gets no sample beyond the window's last but one: its interpolation near the window's
  /// end must not depend on how far the IMU stream happens to be ahead.
  void feedImu(std::size_t last) {
    const auto& imu = screen_.samples();
    const auto& extra = screen_.extraNoise();
    for (; fed_ < imu.size() && fed_ <= last; ++fed_)
      filter_->addImu(imu[fed_], extra[fed_].gyro, extra[fed_].accel);
  }

  /// The open node's points received so far, those of [lo, hi) (the last node: [lo, t_k]): each
  /// frame's part goes to the recorder at once, the usability test comes when the node closes.
  /// `kStrided`: one return in stride_ (counted over the window's returns) is used, else every
  /// one.
  template <bool kStrided>
  void takePoints(Diagnostics& diag, double t_k, double lo, double hi, bool last) {
    const std::size_t stride = static_cast<std::size_t>(stride_);
    while (seq_.normalize(cursor_)) {
      const MeasurementSequencer::FrameRef& frame = seq_.frames()[cursor_.f];
      const DopplerPoint* pts = frame.points->data();
      const std::size_t n = frame.points->size();
      const double stamp = frame.stamp;
      // The frame's times do not decrease (the sequencer checks it): the end of the node's
      // interval, and before it the returns before the window (passed over), by bisection.
      auto time = [stamp](const DopplerPoint& q) {
        return stamp + static_cast<double>(q.time_offset);
      };
      const std::size_t end =
          static_cast<std::size_t>(std::partition_point(pts + cursor_.p, pts + n,
                                                        [&](const DopplerPoint& q) {
                                                          const double t = time(q);
                                                          return last ? !(t > t_k) : !(t >= hi);
                                                        }) -
                                   pts);
      const std::size_t p = static_cast<std::size_t>(
          std::partition_point(pts + cursor_.p, pts + end,
                               [&](const DopplerPoint& q) { return time(q) < lo; }) -
          pts);
      const std::size_t count = end - p;
      diag.points_seen += count;
      if constexpr (kStrided) {
        // The returns the stride uses: those at which the counter is zero, stride apart.
        const std::size_t first = (stride - stride_counter_) % stride;
        const std::size_t used = first < count ? (count - first + stride - 1) / stride : 0;
        if (used > 0) recorder_.add(pts + p + first, used, stride, stamp, t_k);
        diag.points_skipped += count - used;
        stride_counter_ = (stride_counter_ + count) % stride;
      } else {
        if (count > 0) recorder_.add(pts + p, count, 1, stamp, t_k);
      }
      cursor_.p = end;
      if (end < n) break;
    }
  }

  /// The IMU sample (index into the screened stream) of node i.
  std::size_t nodeSample(std::size_t i) const { return k_first_ + filter_->nodeSample(i); }

  void run(InitResult& r) {
    const auto& imu = screen_.samples();
    while (true) {
      const std::size_t k = nodeSample(filter_->nodes() - 1);
      if (!node_open_) {
        // The window rule (config.h), with the stream's nominal interval: this sample closes
        // the window, or the next one is beyond.
        const double duration = cfg_.window.duration, h = screen_.interval();
        last_ = k > k_first_ &&
                windowSampleAt(imu[k_first_].t, imu[k].t, h, duration) == WindowSample::Last;
        // The next node: node_stride_ samples on, or at the window's last sample before that.
        std::size_t next = k;
        for (std::size_t j = k + 1; !last_ && next == k; ++j) {
          if (j >= imu.size()) return;  // the node's interval needs the samples up to the next
          // A gap the screen did not bridge, inside the window: the window would end at it.
          if (imu[j].t - imu[j - 1].t > std::max(cfg_.imu.max_bridged_gap, 2.5 * h)) {
            fail(r, InitStatus::NotEnoughData,
                 "IMU gap of " + formatSignificant(imu[j].t - imu[j - 1].t, 3) + " s at " +
                     input::formatStamp(imu[j - 1].t) + " (" +
                     formatSignificant(imu[j - 1].t - t_ref_, 3) + " s into the window of " +
                     formatSignificant(duration, 3) + " s): longer than [imu] max_bridged_gap (" +
                     formatSignificant(cfg_.imu.max_bridged_gap, 3) + " s), it is not bridged");
            return;
          }
          switch (windowSampleAt(imu[k_first_].t, imu[j].t, h, duration)) {
            case WindowSample::Outside:  // the window closed with the sample before
              if (j == k + 1)
                last_ = true;
              else
                next = j - 1;
              break;
            case WindowSample::Last:
              next = j;
              break;
            case WindowSample::Inside:
              if (j == k + node_stride_) next = j;
              break;
          }
        }
        // The cubic interpolation of the IMU up to the next node wants the sample after it.
        if (!last_ && next + 1 >= imu.size() && !seq_.finished()) return;
        if (last_) k_window_last_ = k;
        feedImu(last_ ? k + 1 : next + 1);
        filter_->beginNode(last_, last_ ? 0 : next - k_first_);
        node_open_ = true;
      }
      const bool last = last_;
      const double t_k = imu[k].t;
      const double lo = t_k - filter_->intervalBefore();
      const double hi = t_k + filter_->intervalAfter();
      if (stride_ == 1)
        takePoints<false>(r.diag, t_k, lo, hi, last);
      else
        takePoints<true>(r.diag, t_k, lo, hi, last);
      if (!seq_.lidarPassed(last ? t_k + 1e-9 : hi)) return;  // more points may come
      filter_->setReturns(recorder_.closeNode(usable_, r.diag.points_skipped));
      filter_->update();
      const std::size_t used_before = r.diag.points_used, rejected_before = r.diag.points_rejected;
      recorder_.judgeNode(*filter_, r.diag.points_used, r.diag.points_rejected);
      if (acceptanceCollapsed(r.diag.points_used - used_before,
                              r.diag.points_rejected - rejected_before)) {
        fail(r, InitStatus::InconsistentData,
             "the LiDAR returns from " + input::formatStamp(collapse_t_) + " (" +
                 formatSignificant(collapse_t_ - t_ref_, 3) +
                 " s into the window) on contradict the IMU propagation (their acceptance fell "
                 "from " +
                 formatSignificant(100.0 * collapse_from_, 2) + " % to " +
                 formatSignificant(100.0 * collapse_to_, 2) +
                 " %): an IMU fault the screen did not catch ([imu] fault_sigmas, accel_range, "
                 "gyro_range), or a sudden change of the scene");
        return;
      }
      const std::size_t node = recorder_.nodes() - 1;
      const bool was_rest = rest_.atRest();
      // The rest tracker sees every sample after the previous node up to this one (a synthetic
      // reading, ImuScreen, stays out of its noise); t_moved: the one at which it saw the motion.
      const std::size_t k_prev = node > 0 ? nodeSample(node - 1) : k - 1;
      const auto& extra = screen_.extraNoise();
      bool rest = was_rest;
      double t_moved = t_k;
      for (std::size_t j = k_prev + 1; j <= k && rest; ++j) {
        rest = rest_.update(imu[j], !extra[j].gyro_synthetic, !extra[j].accel_synthetic);
        t_moved = imu[j].t;
      }
      if (was_rest && !rest) {
        // The IMU shows motion only once it has grown beyond its noise: the last nodes held at
        // rest may already have moved (a gentle start). The smoother does without their rest.
        filter_->cancelRestFrom(t_moved - kRestBackdating);
        // Every node before this one was at rest (the rest ends once).
        std::size_t backdated = node_rest_.size();
        while (backdated > 0 && imu[nodeSample(backdated - 1)].t >= t_moved - kRestBackdating)
          node_rest_[--backdated] = false;
        // Their returns were not seen from a standing sensor after all: their accepted ones out
        // of the rest cells, last first.
        for (std::size_t j = node_rest_.size(); j-- > backdated;) {
          const WindowRecorder::NodeReturns nr = recorder_.node(j);
          for (std::size_t i = nr.end - nr.begin; i-- > 0;)
            if (nr.cell[i] != WindowRecorder::kNoCell)
              rest_cells_.remove(nr.cell[i], static_cast<double>(nr.residual[i]));
        }
        r.diag.static_duration = t_moved - t_ref_;  // when the IMU showed the motion
        r.diag.zero_rate_duration = r.diag.static_duration;
      }
      // The node's gyro samples measure the bias (the filter leaves out those the screen
      // interpolated).
      if (rest)
        filter_->updateRest(cfg_.joint.rest_velocity_sigma,
                            cfg_.joint.zero_rate_at_rest ? filter_->params().gyro_sigma : 0.0);
      if (rest) r.diag.static_duration = r.diag.zero_rate_duration = t_k - t_ref_;
      node_rest_.push_back(rest);
      // A rest node's accepted returns are in the rest cells as long as it stays one.
      if (rest) {
        const WindowRecorder::NodeReturns nr = recorder_.node(node);
        for (std::size_t i = 0; i < nr.end - nr.begin; ++i)
          if (nr.cell[i] != WindowRecorder::kNoCell)
            rest_cells_.add(nr.cell[i], static_cast<double>(nr.residual[i]));
      }
      ++r.diag.gyro_updates;
      node_open_ = false;
      if (last) {
        finalize(r);
        return;
      }
      // Once, at kEarlySmoothing of the window: smooth what has been received, so that the final
      // smoothing (what an online user waits for) starts from a good linearization, and make its
      // first forward pass over these nodes now (ahead): the final one computes the rest.
      if (!early_smoothed_ && t_k - t_ref_ >= kEarlySmoothing * cfg_.window.duration) {
        updateNoise();
        const double t0 = wallSeconds();
        filter_->smooth(kEarlyLooseness, true);
        // The calibration test's pass over these nodes too: the closing call continues it.
        double rot = 0, dt = 0;
        if (calibrationTestStd(rot, dt)) filter_->testCalibrationAhead(rot, dt);
        r.diag.time_solver += wallSeconds() - t0;
        r.diag.early_smoothing_to = hi - t_ref_;
        early_smoothed_ = true;
      }
      filter_->predict();
    }
  }

  void finalize(InitResult& r) {
    phase_ = Phase::Done;
    const double t_solve = wallSeconds();
    Diagnostics& diag = r.diag;
    rejectMovingDirections(r);  // before the counts below: they are of the returns used
    const auto& imu = screen_.samples();
    const double T = imu[k_window_last_].t - t_ref_;
    diag.window_duration = T;
    if (!screenVerdict(r)) return;
    diag.update_rate_hz = T > 0 ? static_cast<double>(diag.points_used + diag.gyro_updates) / T : 0;
    for (const auto& f : seq_.frames()) {
      if (f.points->empty()) continue;
      const double a = f.stamp + static_cast<double>(f.points->front().time_offset);
      const double b = f.stamp + static_cast<double>(f.points->back().time_offset);
      if (b >= t_ref_ && a <= imu[k_window_last_].t) ++diag.frames_in_window;
    }
    if (diag.points_used < 10 && !diag.static_start) {
      fail(r, InitStatus::NoDoppler, "no Doppler return passed the gate in the window");
      return;
    }
    updateNoise();
    diag.iterations = filter_->smooth();
    if (restContradicted()) {
      // The IMU showed rest to the end, but the returns say the sensor moves: a start too gentle
      // for the accelerometer, or moving objects' returns pulling a standing sensor's velocity.
      // The state is that of a moving sensor, without the zero velocity; the gyro, which showed
      // no rotation, still measures its bias.
      filter_->cancelRestFrom(-std::numeric_limits<double>::infinity(), true);
      std::fill(node_rest_.begin(), node_rest_.end(), false);
      diag.static_duration = 0;
      diag.iterations += filter_->smooth();
      rest_withdrawn_ = true;
    }
    // The nodes' smoothed LiDAR velocities, for the tests below: computed once per smoothing.
    std::vector<DopplerInertialFilter::Vec9> Q = filter_->lidarVelocityPolynomials();
    for (int round = 0; round < 3 && rejectMovingCells(r, Q); ++round) {
      diag.iterations += filter_->smooth();
      Q = filter_->lidarVelocityPolynomials();
    }
    finalDopplerNoise(diag, Q);
    reportNoise(diag);
    diag.time_solver += wallSeconds() - t_solve;
    const std::size_t N = filter_->nodes();
    const FilterState& x = filter_->state(N - 1);
    const std::size_t used = filter_->acceptedPointsTotal();
    diag.doppler_residual_rms =
        used > 0 ? std::sqrt(filter_->residualSumOfSquares(Q) / static_cast<double>(used)) : 0.0;
    const double inflation = testNodeResiduals(diag, Q);
    node_residuals_inflated_ = inflation > 1.0;
    std::ostringstream rep;
    rep << "joint: " << N << " nodes, " << diag.iterations << " smoother iterations";
    diag.solver_report = rep.str();

    // A solve that diverged is no state, whatever the tests above read from it.
    const bool finite = x.R_wb.allFinite() && x.p_w.allFinite() && x.v_w.allFinite() &&
                        x.b_g.allFinite() && x.b_a.allFinite() && std::isfinite(x.dt_l) &&
                        filter_->covariance().allFinite();
    if (!finite) {
      fail(r, InitStatus::SolverFailed,
           "the smoother's solution is not finite (it diverged after " +
               std::to_string(diag.iterations) + " iterations): no state is reported");
      return;
    }
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
    s.cov.topLeftCorner<15, 15>() = filter_->covariance().topLeftCorner<15, 15>();
    s.cov.topLeftCorner<15, 15>() *= inflation;
    s.cov.block<3, 3>(kGrav, kGrav).diagonal().setConstant(1e-6);  // fixed by the world frame
    s.cov = 0.5 * (s.cov + s.cov.transpose()).eval();
    // The clock offset: determined by the data where its std fell below half the configured
    // prior's; otherwise it stays near the prior's mean, and the covariance above already carries
    // its share (the offset is in the filter's state).
    const double tos = cfg_.joint.time_offset_sigma;
    s.time_offset = x.dt_l;
    s.time_offset_sigma =
        tos > 0 ? std::sqrt(std::max(
                      0.0, inflation * filter_->covariance()(DopplerInertialFilter::kTime,
                                                             DopplerInertialFilter::kTime)))
                : 0.0;
    s.time_offset_estimated = tos > 0 && s.time_offset_sigma < 0.5 * tos;

    // Trajectory and velocities at every node; the map with the final node poses.
    r.trajectory.clear();
    r.velocities.clear();
    for (std::size_t k = 0; k < N; ++k) {
      const FilterState& xk = filter_->state(k);
      const ImuSample& sk = imu[nodeSample(k)];
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
      // The body velocity's sigma from the node's covariance (the filter's, given the data up
      // to the node: at the last node the state's, before it wider than the smoothed one),
      // scaled as the state's is.
      v.sigma_v_b = (inflation * bodyVelocityCovariance(xk, filter_->nodeCovariance(k)))
                        .diagonal()
                        .cwiseSqrt();
      r.velocities.push_back(v);
    }
    addWarnings(r);
    map_pending_ = true;  // completeMap(): the state does not wait for the map
  }

  /// The backstop for an IMU fault the screen missed: integrated, it moves the prediction by
  /// more than the gate, and the returns of every later node are refused. Fed with each node's
  /// accepted and refused returns (nodes of at least kMinReturns); true once kNodes nodes in a
  /// row accept under a quarter of the median share of the kHistory nodes before them (at least
  /// half). A moving object entering the view lowers the share over many nodes, not at once.
  bool acceptanceCollapsed(std::size_t accepted, std::size_t refused) {
    constexpr std::size_t kMinReturns = 50, kHistory = kAcceptanceHistory, kNodes = 3;
    const std::size_t n = accepted + refused;
    if (n < kMinReturns) return false;
    const double share = static_cast<double>(accepted) / static_cast<double>(n);
    if (acceptance_count_ >= kHistory) {
      std::array<double, kHistory> v = recent_acceptance_;  // the median is the ring's in any order
      std::nth_element(v.begin(), v.begin() + kHistory / 2, v.end());
      const double median = v[kHistory / 2];
      if (median >= 0.5 && share < 0.25 * median) {
        if (collapsed_nodes_ == 0) {
          collapse_t_ = screen_.samples()[nodeSample(filter_->nodes() - 1)].t;
          collapse_from_ = median;
        }
        collapse_to_ = share;
        return ++collapsed_nodes_ >= kNodes;
      }
    }
    collapsed_nodes_ = 0;
    recent_acceptance_[acceptance_count_ % kHistory] = share;
    ++acceptance_count_;
    return false;
  }

  /// The IMU screen's findings inside the window (ImuScreen): counted in the diagnostics and
  /// warned of; the window declines when more of its samples than [imu] max_fault_share are
  /// faults or more than [imu] max_bridged_gap is missing in all. Returns whether it goes on.
  bool screenVerdict(InitResult& r) {
    const auto& imu = screen_.samples();
    const double t_end = imu[k_window_last_].t;
    Diagnostics& diag = r.diag;
    const ImuFault* first = nullptr;
    double last_t = -std::numeric_limits<double>::infinity();
    for (const ImuFault& f : screen_.faults()) {
      if (f.t < t_ref_ || f.t > t_end) continue;
      if (first == nullptr) first = &f;
      if (f.t != last_t) ++diag.imu_faults;  // a sample faulty in both sensors counts once
      last_t = f.t;
    }
    const ImuGap* longest = nullptr;
    for (const ImuGap& g : screen_.gaps()) {
      if (!g.bridged || g.t < t_ref_ || g.t >= t_end) continue;
      diag.imu_gap_s += g.length;
      if (longest == nullptr || g.length > longest->length) longest = &g;
    }
    const std::size_t samples = k_window_last_ - k_first_ + 1;
    if (first != nullptr) {
      const std::string what =
          std::to_string(diag.imu_faults) + " of the window's " + std::to_string(samples) +
          " IMU samples rejected as faults (the first at " + input::formatStamp(first->t) + ", " +
          formatSignificant(first->t - t_ref_, 3) +
          " s into the window: " + (first->accel ? "accelerometer " : "gyro ") +
          formatSignificant(first->magnitude, 3) + (first->accel ? " m/s^2" : " rad/s") +
          (first->out_of_range ? " beyond its range" : " from what its neighbours imply") + ")";
      if (static_cast<double>(diag.imu_faults) >
          cfg_.imu.max_fault_share * static_cast<double>(samples)) {
        fail(r, InitStatus::NotEnoughData,
             what + ": more than [imu] max_fault_share (" +
                 formatSignificant(100.0 * cfg_.imu.max_fault_share, 3) +
                 " %); the IMU is not trusted");
        return false;
      }
      r.state.warnings.push_back(what + ": interpolated with their uncertainty, not integrated");
    }
    if (longest != nullptr) {
      const std::string what = "IMU gaps of " + formatSignificant(diag.imu_gap_s, 3) +
                               " s in all inside the window (the longest " +
                               formatSignificant(longest->length, 3) + " s at " +
                               input::formatStamp(longest->t) + ", " +
                               formatSignificant(longest->t - t_ref_, 3) + " s into the window)";
      if (diag.imu_gap_s > cfg_.imu.max_bridged_gap + 1e-9) {
        fail(r, InitStatus::NotEnoughData,
             what + ": more than [imu] max_bridged_gap (" +
                 formatSignificant(cfg_.imu.max_bridged_gap, 3) + " s) is missing");
        return false;
      }
      r.state.warnings.push_back(what + " bridged by interpolation; the covariance includes it");
    }
    return true;
  }

  void completeMap(InitResult& r) override {
    if (!map_pending_) return;
    map_pending_ = false;
    recorder_.finish(*filter_, screen_.samples(), k_first_, cfg_.extrinsics, r);
  }

  /// The noise the data show so far, for the next smoothing: the IMU's from its rest samples (a
  /// static start), else from the ladder of differences of the samples fed so far (each sensor
  /// where it tells: imuMotionNoise). A change of less than a tenth (within the estimate's own
  /// uncertainty, and cheaper than the re-solve every node's rows would need) is not made.
  void updateNoise() {
    const DopplerInertialFilterParams& p = filter_->params();
    constexpr double kChange = 0.1;
    auto moved = [](double x, double y) { return std::abs(x / y - 1.0) > kChange; };
    double g = 0, a = 0, d = 0;
    if (imu_noise_from_rest_) {
      g = rest_.gyroNoise().sigma;
      a = rest_.accelNoise().sigma;
    } else {  // the data's where they tell, else (again) the configured value
      gyro_motion_ = motionNoise(false, cfg_.imu.gyro_sigma);
      accel_motion_ = motionNoise(true, cfg_.imu.accel_sigma);
      g = gyro_motion_.sigma > 0 ? gyro_motion_.sigma : cfg_.imu.gyro_sigma;
      a = accel_motion_.sigma > 0 ? accel_motion_.sigma : cfg_.imu.accel_sigma;
    }
    if (!moved(g, p.gyro_sigma)) g = 0;
    if (!moved(a, p.accel_sigma)) a = 0;
    // The Doppler: the kept returns' residuals against each node's update, cut by the second
    // gate at regate_sigma of their std.
    const DopplerInertialFilter::ForwardResiduals f = filter_->forwardResiduals();
    if (f.returns >= kMinNoiseReturns) {
      const double ms = f.rss / static_cast<double>(f.returns);
      const NoisePosterior n =
          dopplerNoise(untruncatedSigma(ms, p.regate_sigma * p.doppler_sigma),
                       static_cast<double>(f.returns), dopplerBelowConfigured());
      if (moved(n.sigma, p.doppler_sigma)) {
        doppler_noise_ = n;
        d = n.sigma;
      }
    }
    if (g > 0 || a > 0 || d > 0) filter_->setNoise(d, g, a);
  }

  /// A moving IMU's noise of one sensor from the samples fed to the filter, combined with the
  /// configured value (zero where the motion hides it).
  NoisePosterior motionNoise(bool accel, double declared) const {
    const MotionNoise m =
        (accel ? accel_ladder_ : gyro_ladder_)
            .extend(screen_.samples(), k_first_, fed_, screen_.interval(), &screen_.extraNoise());
    return m.sigma > 0 ? combineNoise(declared, m.sigma, m.dof) : NoisePosterior{};
  }

  /// The Doppler noise at the start: the start decision's robust scale of its residuals (its
  /// median absolute residual has the information of ~37 % as many normal samples).
  void startDopplerNoise(const StartHypothesis& h) {
    doppler_noise_ = NoisePosterior{};
    if (h.residual_scale_returns < kMinNoiseReturns || !(h.residual_scale > 0)) return;
    constexpr double kMedianEfficiency = 0.37;
    doppler_noise_ = dopplerNoise(
        h.residual_scale, kMedianEfficiency * static_cast<double>(h.residual_scale_returns), false);
  }

  /// The Doppler noise an estimate with `dof` degrees of freedom gives, within the prior's range
  /// of the configured one (a quantized Doppler at rest reads exact zeros: its residuals say
  /// nothing of its noise).
  NoisePosterior dopplerNoise(double estimate, double dof, bool below_configured) const {
    const double declared = cfg_.doppler.doppler_sigma;
    if (!below_configured && !(estimate > declared)) return {declared, 0.0, declared};
    const double e =
        std::clamp(estimate, declared / kNoisePriorSpread, declared * kNoisePriorSpread);
    return combineNoise(declared, e, dof);
  }

  /// Whether the Doppler noise may be taken below the configured one: the residuals of single
  /// returns do not show an error that a node's returns share (vibration, a radar scan's common
  /// error, which a configured value may hold on purpose); the test of the nodes' residuals
  /// (testNodeResiduals) does, and scales the covariance up by it, but only with at least its
  /// kMinReturns returns per node. Sparser returns keep the configured value as a floor.
  bool dopplerBelowConfigured() const {
    const std::size_t nodes = filter_ ? filter_->nodes() : 0;
    constexpr std::size_t kReturnsPerNode = 30;
    return nodes > 0 && filter_->forwardResiduals().returns >= kReturnsPerNode * nodes;
  }

  /// After the final smoothing: the Doppler noise from the smoothed residuals (Q: the nodes'
  /// polynomials); when it moved by more than 5 % from the one used, the window is solved again
  /// with it. Returns whether it was.
  bool finalDopplerNoise(Diagnostics& diag, std::vector<DopplerInertialFilter::Vec9>& Q) {
    const std::size_t used = filter_->acceptedPointsTotal();
    if (used < kMinNoiseReturns) return false;
    const double used_sigma = filter_->params().doppler_sigma;
    const double ms = filter_->residualSumOfSquares(Q) / static_cast<double>(used);
    const NoisePosterior n =
        dopplerNoise(untruncatedSigma(ms, filter_->params().regate_sigma * used_sigma),
                     static_cast<double>(used), dopplerBelowConfigured());
    doppler_noise_.rel_sigma = n.rel_sigma;
    // The data's value is the one used unless the configured one was kept as a floor.
    doppler_from_data_ = n.rel_sigma > 0;
    constexpr double kChange = 0.05;
    if (!(std::abs(n.sigma / used_sigma - 1.0) > kChange)) return false;
    doppler_noise_ = n;
    filter_->setNoise(n.sigma, 0, 0);
    diag.iterations += filter_->smooth();
    Q = filter_->lidarVelocityPolynomials();
    return true;
  }

  /// The noises the final smoothing uses, with their source, in diag.noise.
  void reportNoise(Diagnostics& diag) const {
    const DopplerInertialFilterParams& p = filter_->params();
    NoiseReport& n = diag.noise;
    n.gyro = {p.gyro_sigma, 0.0, cfg_.imu.gyro_sigma, NoiseUsed::Source::Declared};
    n.accel = {p.accel_sigma, 0.0, cfg_.imu.accel_sigma, NoiseUsed::Source::Declared};
    n.doppler = {p.doppler_sigma, 0.0, cfg_.doppler.doppler_sigma, NoiseUsed::Source::Declared};
    if (imu_noise_from_rest_) {
      n.gyro.rel_sigma = rest_.gyroNoise().rel_sigma;
      n.accel.rel_sigma = rest_.accelNoise().rel_sigma;
      n.gyro.source = n.accel.source = NoiseUsed::Source::DataRest;
    } else {
      if (gyro_motion_.sigma > 0)
        n.gyro = {p.gyro_sigma, gyro_motion_.rel_sigma, cfg_.imu.gyro_sigma,
                  NoiseUsed::Source::DataMoving};
      if (accel_motion_.sigma > 0)
        n.accel = {p.accel_sigma, accel_motion_.rel_sigma, cfg_.imu.accel_sigma,
                   NoiseUsed::Source::DataMoving};
    }
    if (doppler_from_data_) {
      n.doppler.rel_sigma = doppler_noise_.rel_sigma;
      n.doppler.source = NoiseUsed::Source::Data;
    }
  }

  /// The nodes' Doppler residuals against the noise model (DopplerInertialFilter::nodeResiduals,
  /// nodes of at least kMinReturns returns, so that their sums are near Gaussian): their
  /// chi-square per degree of freedom in diag.node_residual_ratio. Above the 99.9 % quantile the
  /// returns of each IMU sample share an error the model leaves out; the state's covariance is
  /// then optimistic by about that ratio, and the returned factor (else 1) scales it: the
  /// variance factor of least squares, which keeps the states (right to one or two bounds in
  /// such cases) with a covariance that covers them.
  double testNodeResiduals(Diagnostics& diag,
                           const std::vector<DopplerInertialFilter::Vec9>& Q) const {
    constexpr std::size_t kMinReturns = 30;
    constexpr int kMinDof = 30;  // ten nodes: fewer leave the ratio itself too noisy
    const DopplerInertialFilter::NodeResiduals t = filter_->nodeResiduals(kMinReturns, Q);
    diag.node_residual_ratio = t.dof > 0 ? t.chi2 / t.dof : 0.0;
    if (t.dof < kMinDof) return 1.0;
    constexpr double kZ999 = 3.090;  // standard normal, 99.9 %
    return t.chi2 > detail::chi2Quantile(t.dof, kZ999) ? diag.node_residual_ratio : 1.0;
  }

  /// Whether the returns contradict the rest the IMU showed up to the window's last node: the
  /// smoothed body velocity there, with the rest knowledge in it, is still significantly non-zero
  /// (chi-square 3 dof, 99.9 %) against its own covariance. The Doppler of many returns resolves
  /// a fraction of a mm/s; an accelerometer misses a start that gains 0.02 m/s in half a second.
  bool restContradicted() const {
    if (node_rest_.empty() || !node_rest_.back()) return false;
    const FilterState& x = filter_->state(filter_->nodes() - 1);
    const Vec3 v_b = x.R_wb.transpose() * x.v_w;
    const Mat3 C = bodyVelocityCovariance(x, filter_->covariance());
    constexpr double kChi2Quantile999Dof3 = 16.27;
    return v_b.dot(C.ldlt().solve(v_b)) > kChi2Quantile999Dof3;
  }

  /// rejectMovingCells' per-cell sums, zero, made at the start rather than in the call that
  /// closes the window (their first pages would be faulted in there).
  void prepareMovingCellSums() {
    // The cells and a spare slot (WindowRecorder::kNoCell, one past them, never coherent), so
    // that every return's cell can be read without a branch on its verdict.
    constexpr std::size_t kSlots = RestCells::kCells + 1;
    if (span_sum_.size() == kSlots) return;
    span_sum_.assign(kSlots, 0.0);
    span_count_.assign(kSlots, 0);
    span_coherent_.assign(kSlots, 0);
    span_touched_.assign(kSlots, 0);
  }

  /// The moving sensor's counterpart of rejectMovingDirections, after a smoothing: within a short
  /// span (kSpan) a moving sensor sees each part of the world in nearly the same direction too,
  /// and the world's residuals against the smoothed motion average to zero there. The returns of
  /// an object moving slowly along their lines of sight pass every gate but share a non-zero mean
  /// residual by direction and range. Those cells' returns leave the estimate when they are
  /// many; returns whether they did (the window is then smoothed again). A wrong calibration
  /// leaves direction-dependent residuals of the world itself: its cells may go too, and the
  /// calibration test still tells. Qs: the nodes' smoothed LiDAR velocities
  /// (DopplerInertialFilter::lidarVelocityPolynomials).
  bool rejectMovingCells(InitResult& r, const std::vector<DopplerInertialFilter::Vec9>& Qs) {
    constexpr double kSpan = 0.05;  // [s]
    constexpr double kSigmas = 4.0;
    constexpr std::uint32_t kMinCount = 8;
    constexpr std::size_t kMinReturns = 200;
    const double sigma = filter_->params().doppler_sigma;
    const auto& imu = screen_.samples();
    WindowRecorder& rec = recorder_;
    const std::size_t nodes = rec.nodes();
    prepareMovingCellSums();
    std::uint32_t* touched = span_touched_.data();  // the span's slots, in the order first seen
    struct Return {
      std::size_t node, j;  ///< node's j-th return
    };
    std::vector<Return> coherent;
    auto moving = [this](std::size_t k) { return !(k < node_rest_.size() && node_rest_[k]); };
    std::size_t k = 0;
    while (k < nodes) {
      // One span, from a node with returns: the accepted returns of its moving nodes, their
      // residuals against the smoothed motion summed into their cells, run by run
      // (WindowRecorder::runs: the linear form of a run's sum in the node's polynomial); the
      // sum of their squares, the nodes' (the filter's sums hold the same returns).
      if (rec.node(k).begin == rec.node(k).end) {
        ++k;
        continue;
      }
      const double t_begin = imu[nodeSample(k)].t;
      const std::size_t span_first = k;
      std::size_t slots = 0;
      double sumsq = 0;
      std::size_t total = 0;
      for (; k < nodes && imu[nodeSample(k)].t < t_begin + kSpan; ++k) {
        if (!moving(k)) continue;
        const WindowRecorder::Runs runs = rec.runs(k);
        if (runs.count == 0) continue;
        const double* q = Qs[k].data();
        for (std::size_t i = 0; i < runs.count; ++i) {
          const recorder_kernels::CellRun& run = runs.first[i];
          const std::uint16_t c = run.cell;
          if (span_count_[c] == 0) touched[slots++] = c;
          span_sum_[c] += run.residualSum(q);
          span_count_[c] += run.count;
          total += run.count;
        }
        sumsq += filter_->nodeResidualSumOfSquares(k, Qs[k]);
      }
      // The test of RestCells::coherent, per span: the std from the Doppler noise or, when
      // larger, the span's residual RMS. It is a cell's: cell by cell, then (only if a cell
      // fails it) the returns summed above that are in such a cell, in order.
      bool any = false;
      if (total > 0) {
        const double var = std::max(sigma * sigma, sumsq / static_cast<double>(total));
        const double kk = kSigmas * kSigmas * var;
        for (std::size_t t = 0; t < slots; ++t) {
          const std::uint32_t c = touched[t];
          const std::uint32_t n = span_count_[c];
          const double sum = span_sum_[c];
          const bool coherent_cell = n >= kMinCount && sum * sum > kk * static_cast<double>(n);
          span_coherent_[c] = coherent_cell ? 1 : 0;
          any = any || coherent_cell;
        }
      }
      for (std::size_t f = span_first; any && f < k; ++f) {
        if (!moving(f)) continue;
        const WindowRecorder::NodeReturns nr = rec.node(f);
        for (std::size_t j = 0; j < nr.end - nr.begin; ++j)
          if (span_coherent_[nr.cell[j]] != 0) coherent.push_back({f, j});
      }
      for (std::size_t t = 0; t < slots; ++t) {
        const std::uint32_t c = touched[t];
        span_sum_[c] = 0;
        span_count_[c] = 0;
        span_coherent_[c] = 0;
      }
    }
    // Cells of the world pass the test by chance now and then (development seeds: none in most
    // windows, tens of returns in some): not worth another smoothing. An object's are thousands.
    if (coherent.size() < kMinReturns) return false;
    for (const Return& c : coherent) removeReturn(c.node, c.j, r.diag);
    return true;
  }

  /// Takes node k's j-th recorded return out of the estimate (its node's sums) and out of the
  /// map.
  void removeReturn(std::size_t k, std::size_t j, Diagnostics& diag) {
    const WindowRecorder::NodeReturns nr = recorder_.node(k);
    filter_->removePoint(k, static_cast<double>(nr.tau[j]),
                         Eigen::Vector3f(nr.x[j], nr.y[j], nr.z[j]),
                         static_cast<double>(nr.doppler[j]));
    recorder_.reject(nr.begin + j);
    --diag.points_used;
    ++diag.points_rejected;
  }

  /// Takes the returns of the directions whose residuals, while the sensor stood still, are
  /// coherently non-zero (RestCells) out of the estimate, before the final smoothing. Only rest
  /// nodes: a moving sensor sees the world's parts in changing directions, and there a
  /// calibration error leaves direction-dependent residuals of the world itself.
  void rejectMovingDirections(InitResult& r) {
    if (rest_cells_.total() == 0) return;
    // ~25k cells, a few thousand occupied: a world cell taken for a moving one in a few windows
    // of a hundred, which costs its returns and nothing else.
    constexpr double kSigmas = 4.0;
    constexpr int kMinCount = 4;
    const double sigma = filter_->params().doppler_sigma;
    // The returns in the rest cells: the accepted ones of the nodes still at rest.
    for (std::size_t k = 0; k < recorder_.nodes() && k < node_rest_.size(); ++k) {
      if (!node_rest_[k]) continue;
      const WindowRecorder::NodeReturns nr = recorder_.node(k);
      for (std::size_t j = 0; j < nr.end - nr.begin; ++j) {
        const std::uint16_t c = nr.cell[j];
        if (c == WindowRecorder::kNoCell) continue;
        if (!rest_cells_.coherent(c, sigma, kSigmas, kMinCount)) continue;
        removeReturn(k, j, r.diag);
      }
    }
  }

  /// The verdict on a state: a contradiction of the data beyond what the noise and the priors
  /// allow is not reported as a state (a status says why); milder signs become warnings.
  void addWarnings(InitResult& r) {
    InitialState& s = r.state;
    const Diagnostics& d = r.diag;
    auto fmt = [](double v, int digits = 3) { return formatSignificant(v, digits); };
    const double sigma = filter_->params().doppler_sigma;
    const bool noisy = d.points_used >= 100 && d.doppler_residual_rms > 1.5 * sigma;
    const std::size_t judged = d.points_used + d.points_rejected;
    const double agree = judged > 0 ? static_cast<double>(d.points_used) / judged : 1.0;
    // Physically implausible biases: the data were explained by a model they do not fit.
    const double bound = cfg_.imu.accel_bias_bound;
    const double ba_max = s.b_a.cwiseAbs().maxCoeff();
    if (ba_max > bound) {
      failResult(r, InitStatus::InconsistentData,
                 "the accelerometer bias the data imply (" + fmt(ba_max) +
                     " m/s^2 on one axis) exceeds its plausible bound (" + fmt(bound) +
                     " m/s^2, [imu] accel_bias_bound): moving objects taken for the world, "
                     "a wrong calibration or time offset, or an IMU model that does not hold");
      return;
    }
    const Vec3 dbg = s.b_g - cfg_.imu.gyro_bias_prior;
    const double sg0 = cfg_.imu.gyro_bias_sigma0;
    if (dbg.cwiseAbs().maxCoeff() > 5.0 * sg0) {
      failResult(r, InitStatus::InconsistentData,
                 "the gyro bias the data imply is " + fmt(dbg.cwiseAbs().maxCoeff()) +
                     " rad/s from its prior, more than 5 prior sigmas (" + fmt(sg0) +
                     " rad/s, [imu] gyro_bias_sigma0): a wrong calibration or time "
                     "offset, or moving objects taken for the world");
      return;
    }
    // Few returns agree with the motion, and even those do not fit it: their residuals exceed
    // the Doppler noise, or each node's returns disagree with it as a whole (the sign that is
    // left once the noise is read from the residuals, which then include the motion's error: a
    // handheld start among walkers whose returns were 90 % of the view: 9.6 % agreeing,
    // chi-square per degree of freedom 4.7, the velocity 0.29 m/s off at 2000 of NEES; on 300
    // development runs with noise misdeclared by up to 4x, no run had both signs).
    if ((noisy || node_residuals_inflated_) && judged >= 100 && agree < 0.5) {
      failResult(r, InitStatus::AmbiguousMotion,
                 "only " + fmt(100.0 * agree, 2) +
                     " % of the LiDAR returns agree with the estimated motion and " +
                     (noisy ? "their residuals (RMS " + fmt(d.doppler_residual_rms) +
                                  " m/s) exceed the Doppler noise (" + fmt(sigma) + " m/s)"
                            : "even those disagree with it beyond their noise (chi-square per "
                              "degree of freedom " +
                                  fmt(d.node_residual_ratio) + " per node)") +
                     ": moving objects may fill the view");
      return;
    }
    // The IMU at rest all through, the returns showing motion faster than rest ([start]
    // rest_speed), and few of them agreeing with it: a standing sensor amid moving objects (a
    // crowd, traffic) whose Doppler the estimate followed. (A sensor cruising so smoothly that
    // its IMU looks still sees a world that agrees: the view is mostly static.)
    if (rest_withdrawn_ && judged >= 100 && agree < 0.5 && s.v_b().norm() > cfg_.start.rest_speed) {
      failResult(r, InitStatus::AmbiguousMotion,
                 "the IMU showed rest through the window, but the LiDAR returns show motion (" +
                     fmt(s.v_b().norm()) + " m/s) that only " + fmt(100.0 * agree, 2) +
                     " % of them agree with: moving objects may fill the view of a standing "
                     "sensor");
      return;
    }
    if (rest_withdrawn_)
      s.warnings.push_back(
          "the IMU showed rest through the window, but the LiDAR returns show "
          "the sensor moving (" +
          fmt(s.v_b().norm()) +
          " m/s): the state is that "
          "of a slowly moving sensor, without the rest knowledge");
    if (node_residuals_inflated_)
      s.warnings.push_back(
          "the returns of each IMU sample disagree with the motion by more than the noise model "
          "allows (chi-square per degree of freedom " +
          fmt(d.node_residual_ratio) +
          "): an error common to them that the model leaves out (vibration, time-stamp jitter, "
          "[imu] gyro_sigma set too low for the lever arm); the covariance is scaled up "
          "by that factor");
    if (noisy)
      s.warnings.push_back("the Doppler residuals (RMS " + fmt(d.doppler_residual_rms) +
                           " m/s) exceed the Doppler noise used (" + fmt(sigma) +
                           " m/s, at most ten times the configured one): the extrinsics or the "
                           "LiDAR-IMU time offset may be wrong");
    // Many returns know their RMS to a few per mille (1/sqrt(2n) of it): against a correct noise
    // setting it comes out at 0.985 sigma (the gates cut the tails; development seeds: 0.97-1.015
    // with the calibration right). Beyond 4 % more, the covariance is optimistic by as much, or
    // returns of a moving object passed the gates (a person close to a moving sensor: 1.06).
    constexpr std::size_t kManyReturns = 10000;
    constexpr double kExcessRms = 1.04;
    if (!noisy && d.points_used >= kManyReturns && d.doppler_residual_rms > kExcessRms * sigma)
      s.warnings.push_back("the Doppler residuals (RMS " + fmt(d.doppler_residual_rms) +
                           " m/s over " + std::to_string(d.points_used) +
                           " returns) exceed the Doppler noise used (" + fmt(sigma) +
                           " m/s) by more than chance allows: moving objects may have been "
                           "taken for the world, or [doppler] doppler_sigma is set too low "
                           "(the covariance is then optimistic)");
    // Few returns: under ten per IMU sample (2,000 per second at 200 Hz, a fiftieth of what a
    // 64-line LiDAR gives at 120,000 points/s) the state rests on little Doppler.
    const std::size_t samples = k_window_last_ - k_first_ + 1;
    if (d.points_used < 10 * samples)
      s.warnings.push_back(
          "only " + std::to_string(d.points_used) + " LiDAR returns were used in the window (" +
          fmt(static_cast<double>(d.points_used) / static_cast<double>(samples), 2) +
          " per IMU sample): the state rests on few Doppler measurements");
    if (judged >= 100 && agree < 0.3)
      s.warnings.push_back("only " + fmt(100.0 * agree, 2) +
                           " % of the LiDAR returns in the window agree with the estimated "
                           "motion (moving objects, outliers or a wrong calibration)");
    if (ba_max > 0.7 * bound)
      s.warnings.push_back("the accelerometer bias (" + fmt(ba_max) +
                           " m/s^2 on one axis) is close to its plausible bound (" + fmt(bound) +
                           " m/s^2)");
    if (dbg.cwiseAbs().maxCoeff() > 3.0 * sg0)
      s.warnings.push_back("the gyro bias moved " + fmt(dbg.cwiseAbs().maxCoeff()) +
                           " rad/s from its prior, more than 3 prior sigmas (" + fmt(sg0) +
                           " rad/s)");
    // The configured noise off by more than 2x either way: the user's INI is wrong for this
    // sensor (the state used the data's value).
    const std::pair<const NoiseUsed*, const char*> noises[] = {
        {&d.noise.gyro, "gyro noise ([imu] gyro_sigma"},
        {&d.noise.accel, "accelerometer noise ([imu] accel_sigma"},
        {&d.noise.doppler, "Doppler noise ([doppler] doppler_sigma"}};
    for (const auto& [n, name] : noises) {
      if (n->source == NoiseUsed::Source::Declared || !(n->declared > 0)) continue;
      const double ratio = n->value / n->declared;
      if (ratio > 2.0 || ratio < 0.5)
        s.warnings.push_back(std::string("the data show a ") + name + " " + fmt(n->value) +
                             " against the configured " + fmt(n->declared) +
                             "): the state used the data's value; set it in the configuration");
    }
    testCalibration(r);
  }

  /// The calibration test's prior std (rotation [rad], clock offset [s]); false: no test.
  /// A clock offset the state estimates is tested about the estimate with the state's own prior:
  /// what the warnings name is the calibration taken as exact.
  bool calibrationTestStd(double& rot, double& dt) const {
    const JointParams& e = cfg_.joint;
    rot = e.test_rotation_sigma_deg * kPi / 180.0;
    dt = e.time_offset_sigma > 0 ? e.time_offset_sigma : e.test_time_offset_sigma;
    if (!(rot > 0 || dt > 0)) return false;
    rot = std::max(rot, 1e-7);
    dt = std::max(dt, 1e-7);
    return true;
  }

  /// The calibration test: do the data say the declared LiDAR-IMU calibration is off, and would
  /// an error in it go unnoticed by this window while moving the state by more than users notice?
  void testCalibration(InitResult& r) {
    const JointParams& e = cfg_.joint;
    const bool time_estimated = e.time_offset_sigma > 0;
    double rot = 0, dt = 0;
    if (!calibrationTestStd(rot, dt)) return;
    using F = DopplerInertialFilter;
    const F::CalibrationTest t = filter_->testCalibration(rot, dt);
    if (!t.ok) return;
    auto fmt = [](double v, int digits = 2) { return formatSignificant(v, digits); };
    const double phi_deg = t.correction.segment<3>(F::kRot).norm() * 180.0 / kPi;
    const double dt_ms = t.correction(F::kTime) * 1e3;
    constexpr double kChi2Quantile999Dof4 = 18.47;
    if (t.mahalanobis2 > kChi2Quantile999Dof4) {
      r.state.warnings.push_back(
          "the data say the declared LiDAR-IMU calibration is off: by " + fmt(phi_deg) +
          " deg of rotation and " + fmt(dt_ms) + " ms of clock offset (significance " +
          fmt(std::sqrt(t.mahalanobis2), 3) + " sigma over 4 dof); the state assumes the " +
          (time_estimated ? "declared rotation: check the extrinsics"
                          : "declared one: check the extrinsics and the time stamps"));
      return;
    }
    // Sensitivity: the body velocity's uncertainty with such calibration errors, against its own.
    const std::size_t N = filter_->nodes();
    const FilterState& x = filter_->state(N - 1);
    const double sigma_free = std::sqrt(bodyVelocityCovariance(x, t.covariance).trace());
    const double sigma_fixed = std::sqrt(bodyVelocityCovariance(x, filter_->covariance()).trace());
    constexpr double kVelocityFloor = 0.02;  // [m/s] what a user notices
    if (sigma_free > std::max(3.0 * sigma_fixed, kVelocityFloor))
      r.state.warnings.push_back(
          "this window's motion does not check the LiDAR-IMU calibration: errors of " +
          fmt(e.test_rotation_sigma_deg) + " deg" +
          (time_estimated ? " in its rotation" : " and " + fmt(dt * 1e3) + " ms in it") +
          " would leave the body velocity uncertain by " + fmt(sigma_free, 3) + " m/s (" +
          fmt(sigma_fixed, 2) + " m/s with the calibration exact)");
  }

  const FreeInitConfig& cfg_;
  const MeasurementSequencer& seq_;
  UsablePoints usable_;
  Phase phase_ = Phase::WaitStart;
  std::size_t k_first_ = 0, k_window_last_ = 0;
  std::size_t node_stride_ = 1;  ///< IMU samples from one node to the next ([joint] node_rate)
  double t_ref_ = 0;
  int stride_ = 1;
  std::size_t stride_counter_ = 0;
  MeasurementSequencer::Cursor cursor_;
  bool node_open_ = false;
  bool last_ = false;  ///< the open node is the window's last
  bool early_smoothed_ = false;
  bool rest_withdrawn_ = false;  ///< the returns contradicted the IMU's rest (restContradicted)
  bool imu_noise_from_rest_ = false;  ///< the IMU's noise is read from its rest samples (rest_)
  /// A moving IMU's noise from the samples' differences (updateNoise; sigma 0: not told)
  NoisePosterior gyro_motion_, accel_motion_;
  /// Their ladders' sums over the samples fed so far (each sample's differences taken once).
  mutable MotionNoiseLadder gyro_ladder_{false}, accel_ladder_{true};
  /// The Doppler noise from the data (sigma 0: the configured one is used).
  NoisePosterior doppler_noise_;
  bool doppler_from_data_ = false;  ///< the Doppler noise used is the data's (finalDopplerNoise)
  bool node_residuals_inflated_ = false;  ///< the covariance was scaled (testNodeResiduals)
  bool map_pending_ = false;              ///< a state is out, its map not yet (completeMap)
  std::size_t fed_ = 0;  ///< IMU samples handed to the filter (indices into the sequencer's)
  std::optional<DopplerInertialFilter> filter_;
  ImuScreen screen_;
  /// acceptanceCollapsed: the shares of the last nodes (a ring), and how many were given.
  static constexpr std::size_t kAcceptanceHistory = 10;
  std::array<double, kAcceptanceHistory> recent_acceptance_{};
  std::size_t acceptance_count_ = 0;
  std::size_t collapsed_nodes_ = 0;  ///< ... nodes in a row under a quarter of the median
  double collapse_t_ = 0, collapse_from_ = 0, collapse_to_ = 0;  ///< ... the first of them
  RestTracker rest_;
  std::vector<bool> node_rest_;
  WindowRecorder recorder_;
  RestCells rest_cells_;
  std::vector<double> span_sum_;           ///< rejectMovingCells: residual sums of one span's cells
  std::vector<std::uint32_t> span_count_;  ///< ... and their counts (zero between spans)
  std::vector<std::uint8_t> span_coherent_;  ///< ... whether a cell of the span fails the test
  std::vector<std::uint32_t> span_touched_;  ///< ... the cells the span touched
};

}  // namespace

std::unique_ptr<Pipeline> makeJointPipeline(const FreeInitConfig& config,
                                            const MeasurementSequencer& sequencer) {
  return std::make_unique<JointPipeline>(config, sequencer);
}

}  // namespace freeinit::detail
