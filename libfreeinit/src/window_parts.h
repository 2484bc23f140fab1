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
#include <limits>
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

/// The returns of the window as the filter received them, judged once their node is updated and
/// mapped into the world once the node states are final. Each return is kept as the MapPoint it
/// becomes (in the LiDAR frame and at its offset from its node until finish() maps it in place,
/// so that the window's largest buffer is never held twice), with a small tag beside it.
class WindowRecorder {
 public:
  struct Tag {
    std::uint32_t node;
    std::uint16_t cell;  ///< direction and range cell (RestCells) of an accepted return
    bool accepted;
    bool in_rest_cells;  ///< counted in the rest cells (seen from a standing sensor)
  };
  static constexpr std::uint16_t kNoCell = 0xffff;
  void reserve(std::size_t n) {
    returns_.reserve(n);
    tags_.reserve(n);
  }
  std::size_t size() const { return returns_.size(); }
  /// A return given to the filter's open node.
  void add(std::size_t node, double tau, const DopplerPoint& p) {
    MapPoint m;
    m.p_w = p.p_l;
    m.intensity = p.intensity;
    m.doppler = p.doppler;
    m.time = static_cast<float>(tau);
    returns_.push_back(m);
    tags_.push_back({static_cast<std::uint32_t>(node), kNoCell, false, false});
  }
  /// count consecutive returns of one frame (stamp [s]) given to the open node at once, each as
  /// add(node, stamp + time_offset - t_node, p) takes it.
  void add(std::size_t node, const DopplerPoint* p, std::size_t count, double stamp,
           double t_node) {
    const std::size_t m = returns_.size();
    returns_.resize(m + count);
    tags_.resize(m + count, {static_cast<std::uint32_t>(node), kNoCell, false, false});
    MapPoint* out = returns_.data() + m;
    for (std::size_t i = 0; i < count; ++i) {
      const double t = stamp + static_cast<double>(p[i].time_offset);
      out[i].p_w = p[i].p_l;
      out[i].intensity = p[i].intensity;
      out[i].doppler = p[i].doppler;
      out[i].time = static_cast<float>(t - t_node);
    }
  }
  const Tag& tag(std::size_t i) const { return tags_[i]; }
  Tag& tag(std::size_t i) { return tags_[i]; }
  const Eigen::Vector3f& lidarPoint(std::size_t i) const { return returns_[i].p_w; }
  float tau(std::size_t i) const { return returns_[i].time; }  ///< [s] from its node's time
  float doppler(std::size_t i) const { return returns_[i].doppler; }
  float residual(std::size_t i) const { return returns_[i].residual; }
  void reject(std::size_t i) { tags_[i].accepted = false; }
  /// The verdicts on the returns [begin, end), the open node's in the order given to the
  /// filter, after its update(): accepted or not, the residual, an accepted return's cell
  /// (cell_of: RestCells::cellOf); adds them to the counts.
  template <class CellOf>
  void judgeNode(std::size_t begin, std::size_t end, const DopplerInertialFilter& filter,
                 CellOf cell_of, std::size_t& used, std::size_t& rejected) {
    std::size_t accepted = 0;
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t j = i - begin;
      const bool a = filter.pointAccepted(j);
      accepted += a ? 1 : 0;
      tags_[i].accepted = a;
      returns_[i].residual = static_cast<float>(filter.pointResidual(j));
      tags_[i].cell = a ? static_cast<std::uint16_t>(cell_of(returns_[i].p_w)) : kNoCell;
    }
    used += accepted;
    rejected += (end - begin) - accepted;
  }
  /// Maps every return with the final node states (the body moved by tau, its angular and
  /// linear velocity at the node, between the node and the return), the accepted ones into
  /// r.static_map (the recorder's own buffer, moved), the others into r.rejected. The recorder
  /// is empty afterwards.
  void finish(const DopplerInertialFilter& filter, const std::vector<ImuSample>& imu,
              std::size_t k_first, const Extrinsics& ext, InitResult& r) {
    // In float, as the map is kept: at 100 m its rounding is 0.01 mm. A return at tau from its
    // node is at x_b = p_b + tau (omega x p_b + v_b) in the node's body frame (p_b = R_bl p_l +
    // p_bl), so in the world p_w = A p_l + a + tau (B p_l + b) with, per node, A = R R_bl,
    // a = R p_bl + p, B = R [omega]x R_bl and b = R (omega x p_bl + v_b).
    struct NodeMap {
      Eigen::Matrix3f A, B;
      Eigen::Vector3f a, b;
      float time;  ///< [s] from the state's time (the last node's)
    };
    std::vector<NodeMap> maps(filter.nodes());
    const double t_state = filter.state(filter.nodes() - 1).t;
    for (std::size_t k = 0; k < maps.size(); ++k) {
      const FilterState& x = filter.state(k);
      const Vec3 omega = imu[k_first + k].gyro - x.b_g;
      const Vec3 v_b = x.R_wb.transpose() * x.v_w;
      maps[k] = {(x.R_wb * ext.R_bl).cast<float>(), (x.R_wb * skew(omega) * ext.R_bl).cast<float>(),
                 (x.R_wb * ext.p_bl + x.p_w).cast<float>(),
                 (x.R_wb * (omega.cross(ext.p_bl) + v_b)).cast<float>(),
                 static_cast<float>(x.t - t_state)};
    }
    std::size_t accepted = 0;
    for (const Tag& t : tags_) accepted += t.accepted ? 1 : 0;
    r.rejected.clear();
    r.rejected.reserve(returns_.size() - accepted);
    // Node by node (the recorder holds the returns in node order), its map's coefficients held
    // in registers: every return mapped in place, without branches; then the accepted ones close
    // up in place (the write position never passes the read one) and the others are copied out.
    const std::size_t count = returns_.size();
    for (std::size_t begin = 0; begin < count;) {
      const std::uint32_t node = tags_[begin].node;
      std::size_t end = begin + 1;
      while (end < count && tags_[end].node == node) ++end;
      const NodeMap& m = maps[node];
      const float a00 = m.A(0, 0), a01 = m.A(0, 1), a02 = m.A(0, 2), a10 = m.A(1, 0),
                  a11 = m.A(1, 1), a12 = m.A(1, 2), a20 = m.A(2, 0), a21 = m.A(2, 1),
                  a22 = m.A(2, 2);
      const float b00 = m.B(0, 0), b01 = m.B(0, 1), b02 = m.B(0, 2), b10 = m.B(1, 0),
                  b11 = m.B(1, 1), b12 = m.B(1, 2), b20 = m.B(2, 0), b21 = m.B(2, 1),
                  b22 = m.B(2, 2);
      const float ax = m.a.x(), ay = m.a.y(), az = m.a.z(), bx = m.b.x(), by = m.b.y(),
                  bz = m.b.z(), t_node = m.time;
      MapPoint* ps = returns_.data();
      for (std::size_t i = begin; i < end; ++i) {
        MapPoint& p = ps[i];
        const float x = p.p_w.x(), y = p.p_w.y(), z = p.p_w.z(), tau = p.time;
        // A p_l + a + tau (B p_l + b), each sum in the order Eigen's float products take it.
        const float wx =
            ((a00 * x + a01 * y) + a02 * z) + ax + tau * (((b00 * x + b01 * y) + b02 * z) + bx);
        const float wy =
            ((a10 * x + a11 * y) + a12 * z) + ay + tau * (((b10 * x + b11 * y) + b12 * z) + by);
        const float wz =
            ((a20 * x + a21 * y) + a22 * z) + az + tau * (((b20 * x + b21 * y) + b22 * z) + bz);
        p.p_w = Eigen::Vector3f(wx, wy, wz);
        p.time = t_node + tau;
      }
      begin = end;
    }
    std::size_t kept = 0;
    for (std::size_t i = 0; i < count; ++i) {
      if (tags_[i].accepted)
        returns_[kept++] = returns_[i];
      else
        r.rejected.push_back(returns_[i]);
    }
    returns_.resize(kept);
    r.static_map = std::move(returns_);
    returns_ = {};
    tags_ = {};
  }

 private:
  std::vector<MapPoint> returns_;
  std::vector<Tag> tags_;
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
  /// Squared inner edges of the range bins, (0.5 m 1.25^b)^2 for b = 1 .. kRangeBins - 1: bin b
  /// holds ranges in [0.5 m 1.25^b, 0.5 m 1.25^(b+1)), the first one everything nearer, the last
  /// everything farther.
  static constexpr std::array<float, kRangeBins - 1> kRangeEdges2 = [] {
    std::array<float, kRangeBins - 1> e{};
    double edge = 0.5;
    for (float& x : e) {
      edge *= 1.25;
      x = static_cast<float>(edge * edge);
    }
    return e;
  }();
  /// The edges padded to 32 with infinities, for the bisection in cellOf().
  static constexpr std::array<float, 32> kRangeEdges2Padded = [] {
    std::array<float, 32> e{};
    for (std::size_t i = 0; i < e.size(); ++i)
      e[i] = i < kRangeEdges2.size() ? kRangeEdges2[i] : std::numeric_limits<float>::infinity();
    return e;
  }();
  static constexpr std::uint32_t kCells = kSide * kSide * kRangeBins;
  static_assert(kCells < WindowRecorder::kNoCell, "a cell must fit the recorder's tag");
  RestCells() : sum_(kCells, 0.0), count_(kCells, 0) {}
  static std::uint32_t cellOf(const Eigen::Vector3f& p) {
    const float l1 = std::abs(p.x()) + std::abs(p.y()) + std::abs(p.z());
    const float u0 = p.x() / l1, v0 = p.y() / l1;
    // The lower half folded over (selects, not a branch: the sign of z is as good as random).
    const float fu = (1.0f - std::abs(v0)) * (u0 >= 0 ? 1.0f : -1.0f);
    const float fv = (1.0f - std::abs(u0)) * (v0 >= 0 ? 1.0f : -1.0f);
    const bool lower = p.z() < 0;
    const float u = lower ? fu : u0, v = lower ? fv : v0;
    auto bin = [](float x) {
      return static_cast<std::uint32_t>(
          std::clamp(static_cast<int>((x + 1.0f) * 0.5f * kSide), 0, kSide - 1));
    };
    // Range bins: a person and the wall behind share directions, not ranges. The bin is the
    // number of bin edges at or below the range, on the squared range (no root, no logarithm),
    // found by a branch-free bisection of the sorted edges (five comparisons).
    const float r2 = p.squaredNorm();
    std::uint32_t rb = 0;
    for (std::uint32_t step = 16; step > 0; step /= 2)
      rb += kRangeEdges2Padded[rb + step - 1] <= r2 ? step : 0u;
    rb = std::min<std::uint32_t>(rb, kRangeBins - 1);
    return (bin(u) * kSide + bin(v)) * kRangeBins + rb;
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
    const double var =
        std::max(doppler_sigma * doppler_sigma, sumsq_ / static_cast<double>(total_));
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
