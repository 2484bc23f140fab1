// The joint pipeline's parts that are not the estimator: whether the IMU still shows rest, the
// window's returns as received (for the map), and the test of a standing sensor's returns by
// direction and range. Used by joint_pipeline.cpp only.
#pragma once

#include <freeinit/doppler_inertial_filter.h>
#include <freeinit/initial_state.h>
#include <freeinit/rotation.h>
#include <freeinit/types.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace freeinit::detail {

/// Whether the IMU still shows rest: each new sample is compared with the rest means of the
/// start span. One sample beyond 7 sigma, or the mean of the last four beyond 3 sigma (6 of the
/// mean's sigmas), in the gyro or the accelerometer, ends the rest for the rest of the window.
/// (A datasheet noise 20 % below the unit's makes a false end at most ~1e-5 likely per sample.)
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
    bool moving = dg.norm() > 7.0 * gyro_sigma_ || da.norm() > 7.0 * accel_sigma_;
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

/// The points of the window as the filter received them, judged once their node is updated and
/// mapped into the world once the node states are final.
class WindowRecorder {
 public:
  struct Point {
    std::uint32_t node;
    Eigen::Vector3f p_l;  ///< [m] in the LiDAR frame
    float intensity;
    float doppler;        ///< [m/s]
    float residual;       ///< [m/s] against the node's update
    float tau;            ///< [s] from the node's time
    std::uint32_t cell;   ///< direction and range cell (RestCells) of an accepted point
    bool accepted;
    bool in_rest_cells;   ///< counted in the rest cells (seen from a standing sensor)
  };
  static constexpr std::uint32_t kNoCell = 0xffffffffu;
  void reserve(std::size_t n) { points_.reserve(n); }
  std::size_t size() const { return points_.size(); }
  const std::vector<Point>& points() const { return points_; }
  /// A point given to the filter's open node.
  void add(std::size_t node, double tau, const DopplerPoint& p) {
    points_.push_back({static_cast<std::uint32_t>(node), p.p_l, p.intensity, p.doppler, 0.0f,
                       static_cast<float>(tau), kNoCell, false, false});
  }
  Point& point(std::size_t i) { return points_[i]; }
  /// The verdict on the i-th point recorded; an accepted point's cell.
  void judge(std::size_t i, bool accepted, float residual, std::uint32_t cell) {
    points_[i].accepted = accepted;
    points_[i].residual = residual;
    points_[i].cell = cell;
  }
  void reject(std::size_t i) { points_[i].accepted = false; }
  /// Maps every point with the final node states: the body moved by tau (its angular and linear
  /// velocity at the node) between the node and the point.
  void finish(const DopplerInertialFilter& filter, const std::vector<ImuSample>& imu,
              std::size_t k0, const Extrinsics& ext, InitResult& r) const {
    // In float, as the map is kept: at 100 m its rounding is 0.01 mm. A return at tau from its
    // node is at x_b = p_b + tau (omega x p_b + v_b) in the node's body frame (p_b = R_bl p_l +
    // p_bl), so in the world p_w = A p_l + a + tau (B p_l + b) with, per node, A = R R_bl,
    // a = R p_bl + p, B = R [omega]x R_bl and b = R (omega x p_bl + v_b).
    struct NodeMap {
      Eigen::Matrix3f A, B;
      Eigen::Vector3f a, b;
    };
    std::vector<NodeMap> maps(filter.nodes());
    std::vector<float> node_time(filter.nodes());  // from the state's time (the last node's)
    const double t_state = filter.state(filter.nodes() - 1).t;
    for (std::size_t k = 0; k < maps.size(); ++k) {
      const FilterState& x = filter.state(k);
      const Vec3 omega = imu[k0 + k].gyro - x.b_g;
      const Vec3 v_b = x.R_wb.transpose() * x.v_w;
      maps[k] = {(x.R_wb * ext.R_bl).cast<float>(), (x.R_wb * skew(omega) * ext.R_bl).cast<float>(),
                 (x.R_wb * ext.p_bl + x.p_w).cast<float>(),
                 (x.R_wb * (omega.cross(ext.p_bl) + v_b)).cast<float>()};
      node_time[k] = static_cast<float>(x.t - t_state);
    }
    std::size_t accepted = 0;
    for (const Point& p : points_) accepted += p.accepted ? 1 : 0;
    r.static_map.clear();
    r.rejected.clear();
    r.static_map.reserve(accepted);
    r.rejected.reserve(points_.size() - accepted);
    for (const Point& p : points_) {
      const NodeMap& m = maps[p.node];
      MapPoint out;
      out.p_w = m.A * p.p_l + m.a + p.tau * (m.B * p.p_l + m.b);
      out.intensity = p.intensity;
      out.residual = p.residual;
      out.doppler = p.doppler;
      out.time = node_time[p.node] + p.tau;
      (p.accepted ? r.static_map : r.rejected).push_back(out);
    }
  }

 private:
  std::vector<Point> points_;
};

/// The residuals of the returns while the sensor stands still, by direction: a standing sensor
/// sees each part of the world in the same direction all window long, and the world's residuals
/// there average to zero. A person walking by moves slowly along some lines of sight: each of
/// those returns passes every gate, yet together, window-long, they bend the velocity by a few
/// mm/s. Their directions' mean residual is then far from zero.
/// Cells: an octahedral map of the unit sphere onto a 32 x 32 grid (3-6 deg, no trigonometry),
/// times 24 range bins.
class RestCells {
 public:
  static constexpr int kSide = 32;
  static constexpr int kRangeBins = 24;  // 25 % apart from 0.5 m: 0.5-100 m
  static constexpr float kInvLogStep = 4.4814201f;  // 1 / ln(1.25)
  RestCells() : sum_(kSide * kSide * kRangeBins, 0.0), count_(kSide * kSide * kRangeBins, 0) {}
  static std::uint32_t cellOf(const Eigen::Vector3f& p) {
    const float l1 = std::abs(p.x()) + std::abs(p.y()) + std::abs(p.z());
    float u = p.x() / l1, v = p.y() / l1;
    if (p.z() < 0) {
      const float fu = (1.0f - std::abs(v)) * (u >= 0 ? 1.0f : -1.0f);
      const float fv = (1.0f - std::abs(u)) * (v >= 0 ? 1.0f : -1.0f);
      u = fu;
      v = fv;
    }
    auto bin = [](float x) {
      return static_cast<std::uint32_t>(std::clamp(static_cast<int>((x + 1.0f) * 0.5f * kSide), 0, kSide - 1));
    };
    // Range bins: a person and the wall behind share directions, not ranges.
    const float range = p.norm();
    const int rb = std::clamp(static_cast<int>(std::log(std::max(range, 0.5f) * 2.0f) * kInvLogStep),
                              0, kRangeBins - 1);
    return (bin(u) * kSide + bin(v)) * kRangeBins + static_cast<std::uint32_t>(rb);
  }
  void add(std::uint32_t cell, double residual) {
    sum_[cell] += residual;
    sumsq_ += residual * residual;
    ++count_[cell];
    ++total_;
  }
  void remove(std::uint32_t cell, double residual) {
    sum_[cell] -= residual;
    sumsq_ -= residual * residual;
    --count_[cell];
    --total_;
  }
  /// Whether the cell's mean residual is more than `sigmas` of its std from zero (at least
  /// min_count returns), the std from the Doppler noise or, when larger, the residuals' RMS.
  bool coherent(std::uint32_t cell, double doppler_sigma, double sigmas, int min_count) const {
    const std::uint32_t n = count_[cell];
    if (n < static_cast<std::uint32_t>(min_count) || total_ == 0) return false;
    const double var = std::max(doppler_sigma * doppler_sigma, sumsq_ / static_cast<double>(total_));
    return sum_[cell] * sum_[cell] > sigmas * sigmas * var * static_cast<double>(n);
  }
  std::size_t total() const { return total_; }

 private:
  std::vector<double> sum_;
  std::vector<std::uint32_t> count_;
  double sumsq_ = 0;
  std::size_t total_ = 0;
};

}  // namespace freeinit::detail
