// The joint pipeline's parts that are not the estimator: whether the IMU still shows rest, the
// window's returns as received (for the map), and the test of a standing sensor's returns by
// direction and range. Used by joint_pipeline.cpp only.
#pragma once

#include <freeinit/initial_state.h>
#include <freeinit/rotation.h>
#include <freeinit/types.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "joint/doppler_inertial_filter.h"
#include "joint/noise_estimate.h"
#include "usable_points.h"

namespace freeinit::detail {

/// Whether the IMU still shows rest: each new sample is compared with the rest means of the
/// start span. One sample beyond 7 sigma, or the mean of the last four beyond 3 sigma (6 of the
/// mean's sigmas), in the gyro or the accelerometer, ends the rest for the rest of the window.
/// Sigma is not the configured noise but the 99 % upper bound of the noise the rest samples show
/// (their first differences, the configured value a prior: combineNoise), so that a false end
/// stays below ~1e-5 per sample whatever the IMU's true level. While at rest, every sample adds
/// to that estimate: noise(), the IMU's white noise at rest.
class RestTracker {
 public:
  /// `span_gyro`, `span_accel`: the start span's first differences (its estimate until the
  /// tracker has seen as many); `gyro_sigma`, `accel_sigma`: the configured noises (the prior).
  void start(bool at_rest, const Vec3& gyro_mean, const Vec3& accel_mean,
             const DifferenceSums& span_gyro, const DifferenceSums& span_accel, double gyro_sigma,
             double accel_sigma) {
    at_rest_ = at_rest;
    gyro_mean_ = gyro_mean;
    accel_mean_ = accel_mean;
    span_gyro_ = span_gyro;
    span_accel_ = span_accel;
    declared_gyro_ = gyro_sigma;
    declared_accel_ = accel_sigma;
    gyro_ = DifferenceSums{};
    accel_ = DifferenceSums{};
    recent_g_.fill(Vec3::Zero());  // {} leaves Eigen's elements uninitialized
    recent_a_.fill(Vec3::Zero());
    n_ = 0;
    last_gyro_ = last_accel_ = false;
    updateLimits();
  }
  bool atRest() const { return at_rest_; }
  /// Feeds the next sample (from the start span's first one on); returns atRest().
  /// `gyro_measured`, `accel_measured`: false for a synthetic value (ImuScreen), which the noise
  /// leaves out with the differences touching it (they are smaller than the noise's).
  bool update(const ImuSample& s, bool gyro_measured = true, bool accel_measured = true) {
    if (!at_rest_) return false;
    const Vec3 dg = s.gyro - gyro_mean_, da = s.accel - accel_mean_;
    bool moving = dg.norm() > 7.0 * gyro_limit_ || da.norm() > 7.0 * accel_limit_;
    if (n_ >= 3) {  // the mean of this sample and the three before it
      const Vec3 mg =
          (recent_g_[0] + recent_g_[1] + recent_g_[2] + recent_g_[3] - recent_g_[n_ % 4] + dg) /
          4.0;
      const Vec3 ma =
          (recent_a_[0] + recent_a_[1] + recent_a_[2] + recent_a_[3] - recent_a_[n_ % 4] + da) /
          4.0;
      moving = moving || mg.norm() > 3.0 * gyro_limit_ || ma.norm() > 3.0 * accel_limit_;
    }
    if (moving) {
      at_rest_ = false;
      return false;
    }
    const bool add_g = last_gyro_ && gyro_measured, add_a = last_accel_ && accel_measured;
    if (add_g) gyro_.add(s.gyro - last_.gyro);
    if (add_a) accel_.add(s.accel - last_.accel);
    if ((add_g || add_a) && (gyro_.count > span_gyro_.count || accel_.count > span_accel_.count))
      updateLimits();
    recent_g_[n_ % 4] = dg;
    recent_a_[n_ % 4] = da;
    last_ = s;
    last_gyro_ = gyro_measured;
    last_accel_ = accel_measured;
    ++n_;
    return at_rest_;
  }
  /// The gyro's and the accelerometer's white noise from the rest samples so far (the start
  /// span's until the tracker has seen more), combined with the configured values.
  NoisePosterior gyroNoise() const {
    const DifferenceSums& d = sums(gyro_, span_gyro_);
    return combineNoise(declared_gyro_, d.sigma(), d.dof());
  }
  NoisePosterior accelNoise() const {
    const DifferenceSums& d = sums(accel_, span_accel_);
    return combineNoise(declared_accel_, d.sigma(), d.dof());
  }

 private:
  static const DifferenceSums& sums(const DifferenceSums& own, const DifferenceSums& span) {
    return own.count > span.count ? own : span;
  }
  void updateLimits() {
    gyro_limit_ = gyroNoise().upper99;
    accel_limit_ = accelNoise().upper99;
  }

  bool at_rest_ = false;
  Vec3 gyro_mean_ = Vec3::Zero(), accel_mean_ = Vec3::Zero();
  DifferenceSums span_gyro_, span_accel_, gyro_, accel_;
  double declared_gyro_ = 1, declared_accel_ = 1;
  double gyro_limit_ = 1, accel_limit_ = 1;
  std::array<Vec3, 4> recent_g_{}, recent_a_{};
  ImuSample last_;
  bool last_gyro_ = false, last_accel_ = false;  ///< last_'s readings are measured ones
  std::size_t n_ = 0;
};

/// The per-return loops of the recorder (window_parts.cpp), over one node's returns as arrays;
/// vectorized, with the same results as the scalar forms they replace.
namespace recorder_kernels {
/// Lays count returns out as arrays, p[0], p[step], ... (one frame's, whose stamp [s] is
/// `stamp`): position, intensity, Doppler, tau = stamp + time_offset - t_node (in double,
/// rounded to float), and usable[i] = 1 where `usable` passes the return, else 0. Returns how
/// many it passes.
std::size_t layOut(const DopplerPoint* p, std::size_t count, std::size_t step, double stamp,
                   double t_node, const UsablePoints& usable, float* x, float* y, float* z,
                   float* intensity, float* doppler, float* tau, std::uint8_t* usable_out);
/// RestCells::cellOf of each of n returns at (x, y, z).
void cellsOf(std::size_t n, const float* x, const float* y, const float* z, std::uint16_t* cell);
/// A node's map: a return at tau from its node maps to A p_l + a + tau (B p_l + b), at time
/// t_node + tau from the state (WindowRecorder::finish).
struct NodeMap {
  float A[9], B[9];  ///< row-major
  float a[3], b[3];
  float time;  ///< [s] from the state's time
};
/// Maps n returns in place: (x, y, z) from the LiDAR frame into the world, tau into the time
/// from the state.
void mapReturns(std::size_t n, const NodeMap& m, float* x, float* y, float* z, float* tau);
/// The filter's verdicts on the n returns of its open node, after update(): a rejected
/// return's cell set to no_cell, each residual (rounded to float) into residual. Returns how
/// many it accepted.
std::size_t verdicts(std::size_t n, const DopplerInertialFilter& filter, std::uint16_t no_cell,
                     std::uint16_t* cell, float* residual);
/// Writes n returns of a node, given as its arrays (x, y, z, intensity, Doppler, tau, residual,
/// each n long, one after the other from `arrays`), out as MapPoints: those whose cell is not
/// `no_cell` to map[0, 1, ...], the others to rejected[0, 1, ...]. Returns how many went to the
/// map and adds the others to `dropped`. Each one is also written once more, to the next slot of
/// the list it does not belong to (overwritten by the next one there): map needs room for n,
/// rejected for one more than the rejected ones. map may not overlap the arrays.
std::size_t splitReturns(std::size_t n, const float* arrays, const std::uint16_t* cell,
                         std::uint16_t no_cell, MapPoint* map, MapPoint* rejected,
                         std::size_t& dropped);
/// Consecutive returns of a node in one cell (those between them in no cell skipped), and the
/// sum of their Doppler residuals as a linear form in the node's LiDAR velocity polynomial
/// v(s) = q0 + s (q1 + s q2) (DopplerInertialFilter::lidarVelocityPolynomial, s = tau inv_h):
/// sum_j (doppler_j + d_j . v(s_j)) = doppler + sum_m d_m . q_m with d_m = sum_j s_j^m d_j
/// (d_j = p_l / |p_l|). A node's runs are made once, when it is judged;
/// a test of the whole window against its final motion then reads a run where it read each
/// return (about 15 returns per run on the presets).
struct CellRun {
  std::uint16_t cell = 0;
  std::uint32_t count = 0;  ///< returns
  float doppler = 0;        ///< [m/s] sum of their Doppler
  float d[9] = {};          ///< d_0, d_1, d_2 (x, y, z each)
  /// The sum of the run's residuals against v(s) = q0 + s (q1 + s q2), Q = [q0; q1; q2].
  double residualSum(const double* Q) const {
    double r = doppler;
    for (int i = 0; i < 9; ++i) r += static_cast<double>(d[i]) * Q[i];
    return r;
  }
};
/// The terms d_0, d_1, d_2 of n returns (s = tau inv_h) into terms, as nine arrays of n
/// (d_0's x, y, z, then d_1's, d_2's), in float.
void runTerms(std::size_t n, float inv_h, const float* x, const float* y, const float* z,
              const float* tau, float* terms);
/// The runs of a node's n returns (those whose cell is not no_cell), their terms (runTerms), in
/// order, into runs (room for one per return in a cell). Returns how many. The sums are in
/// float: a run's Doppler sum and its d_0 . q0 nearly cancel, to an error of a few 1e-7 of the
/// Doppler sum, far below what the test of a cell resolves (4 sigma sqrt(n)).
std::size_t cellRuns(std::size_t n, const std::uint16_t* cell, std::uint16_t no_cell,
                     const float* terms, const float* doppler, CellRun* runs);
}  // namespace recorder_kernels

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

/// The returns of the window as the filter received them, judged once their node is updated and
/// mapped into the world once the node states are final. The judged returns are kept in one
/// buffer of the MapPoints they become, node after node, each node's part as arrays (its x, then
/// its y, ..., each over the node's returns: the per-return loops run over contiguous arrays)
/// until finish() maps them in place and turns each node's part into MapPoints, so that the
/// window's largest buffer is never held twice (a few unused slots before the first node let
/// the map be written behind the node being read, see reserve()). Beside it, per return, its cell
/// (an accepted return's direction and range cell, RestCells) or kNoCell (not accepted). The open
/// node's returns stay where the frames hold them until the node closes: they are then tested and
/// laid out in one pass.
class WindowRecorder {
 public:
  /// The cell of a return not accepted: one past RestCells' (a spare slot for loops that add
  /// every return to its cell without a branch on the verdict).
  static constexpr std::uint16_t kNoCell = RestCells::kCells;
  static_assert(RestCells::kCells < 0xffff, "a cell and kNoCell must fit 16 bits");
  /// One judged node's returns: global indices [begin, end), its fields as arrays of end - begin.
  struct NodeReturns {
    std::size_t begin, end;
    const float *x, *y, *z, *intensity, *doppler, *tau, *residual;
    const std::uint16_t* cell;
  };
  /// Room for n returns, and `front` unused slots before the first node's part (before any
  /// node is added): finish() writes the map from the buffer's start, and where it stays `front`
  /// returns or more behind the node it reads, that node's part is read in place rather than
  /// copied aside first. The room is initialized here, at the start, so that its pages are
  /// mapped before the window's nodes are laid out: growing the buffer node by node put a
  /// page fault and a fill into every node, the last one too (what a live user waits for).
  void reserve(std::size_t n, std::size_t front) {
    returns_.assign(front + n, MapPoint{});
    end_ = front;
    node_begin_ = {front};
    front_ = front;
    cells_.assign(n, kNoCell);
    // Runs: about one per 15 returns on the presets; room for twice as many.
    runs_.assign(n / 8, recorder_kernels::CellRun{});
    run_begin_ = {0};
  }
  std::size_t size() const { return node_begin_.back() - front_; }  ///< judged returns
  std::size_t nodes() const { return node_begin_.size() - 1; }      ///< judged nodes
  /// count returns of one frame (stamp [s]), every step-th from p on, given to the open node at
  /// once, each at tau = stamp + time_offset - t_node from the node. The points must stay in
  /// place until the node closes (the sequencer keeps its frames in place).
  void add(const DopplerPoint* p, std::size_t count, std::size_t step, double stamp,
           double t_node) {
    open_runs_.push_back({p, count, step, stamp, t_node});
    open_given_ += count;
  }
  /// Of the returns given to the open node, those `usable` rejects.
  std::size_t openUnusable(const UsablePoints& usable) const {
    std::size_t n = 0;
    for (const Run& run : open_runs_)
      for (std::size_t i = 0; i < run.count; ++i) n += usable(run.points[i * run.step]) ? 0 : 1;
    return n;
  }
  /// Closes the open node: lays its usable returns out as arrays in the node's part of the
  /// buffer, in the order given, adds the others to `skipped`, and returns the arrays (the
  /// filter's input for the node, valid until the next node closes).
  DopplerInertialFilter::OpenArrays closeNode(const UsablePoints& usable, std::size_t& skipped) {
    const std::size_t begin = end_, m = open_given_;
    holdAtLeast(returns_, begin + m);
    float* f = reinterpret_cast<float*>(returns_.data()) + 7 * begin;
    float *x = f, *y = f + m, *z = f + 2 * m, *in = f + 3 * m, *d = f + 4 * m, *tau = f + 5 * m;
    // Each run laid out and tested in a loop the compiler vectorizes; the arrays are m apart
    // while they fill.
    if (verdict_.size() < m) verdict_.resize(m);
    std::size_t j = 0, n = 0;
    for (const Run& run : open_runs_) {
      n += recorder_kernels::layOut(run.points, run.count, run.step, run.stamp, run.t_node, usable,
                                    x + j, y + j, z + j, in + j, d + j, tau + j,
                                    verdict_.data() + j);
      j += run.count;
    }
    // Some not usable: each array's usable returns moved down, n apart (each array after the one
    // before it, whose place it may take; each return to the same place or before it).
    if (n < m) {
      for (std::size_t a = 0; a < 6; ++a) {
        const float* from = f + a * m;
        float* to = f + a * n;
        std::size_t w = 0;
        for (std::size_t i = 0; i < m; ++i) {
          to[w] = from[i];
          w += verdict_[i];
        }
      }
    }
    end_ = begin + n;
    skipped += m - n;
    open_runs_.clear();
    open_given_ = 0;
    return {n, f + 5 * n, f, f + n, f + 2 * n, f + 4 * n};
  }
  /// The verdicts on the returns of the node closed last, after the filter's update(): accepted
  /// or not, the residual, an accepted return's cell; adds them to the counts. Nodes are judged
  /// in order, each once.
  void judgeNode(const DopplerInertialFilter& filter, std::size_t& used, std::size_t& rejected) {
    const std::size_t begin = node_begin_.back(), n = end_ - begin;
    float* f = reinterpret_cast<float*>(returns_.data()) + 7 * begin;
    float* res = f + 6 * n;
    holdAtLeast(cells_, begin - front_ + n);
    std::uint16_t* cell = cells_.data() + (begin - front_);
    recorder_kernels::cellsOf(n, f, f + n, f + 2 * n, cell);
    const std::size_t accepted = recorder_kernels::verdicts(n, filter, kNoCell, cell, res);
    // The node's runs (cellRuns), at its filter node's time scale (the recorder's node k is the
    // filter's).
    const float inv_h = static_cast<float>(filter.normalizedTime(nodes(), 1.0));
    const std::size_t r0 = run_begin_.back();
    holdAtLeast(runs_, r0 + accepted);
    const std::size_t made = makeRuns(n, cell, inv_h, f, r0);
    run_begin_.push_back(r0 + made);
    run_count_.push_back(made);
    run_inv_h_.push_back(inv_h);
    node_begin_.push_back(begin + n);
    accepted_ += accepted;
    used += accepted;
    rejected += n - accepted;
  }
  /// Judged node k's returns.
  NodeReturns node(std::size_t k) const {
    const std::size_t b = node_begin_[k], n = node_begin_[k + 1] - b, i = b - front_;
    const float* f = reinterpret_cast<const float*>(returns_.data()) + 7 * b;
    return {i,         i + n,     f,         f + n,     f + 2 * n,
            f + 3 * n, f + 4 * n, f + 5 * n, f + 6 * n, cells_.data() + i};
  }
  /// Judged node k's runs (cellRuns) over its returns in cells: [first, first + count).
  struct Runs {
    const recorder_kernels::CellRun* first;
    std::size_t count;
  };
  /// (Made again first where returns were rejected since they were made: in place, since they
  /// can only be fewer.)
  Runs runs(std::size_t k) {
    if (run_count_[k] == kStaleRuns) {
      const std::size_t b = node_begin_[k], n = node_begin_[k + 1] - b;
      run_count_[k] =
          makeRuns(n, cells_.data() + (b - front_), run_inv_h_[k],
                   reinterpret_cast<const float*>(returns_.data()) + 7 * b, run_begin_[k]);
    }
    return {runs_.data() + run_begin_[k], run_count_[k]};
  }
  /// Takes an accepted return out of the map (into the rejected returns) and out of its node's
  /// runs.
  void reject(std::size_t i) {
    if (cells_[i] == kNoCell) return;
    cells_[i] = kNoCell;
    --accepted_;
    const auto after = std::upper_bound(node_begin_.begin(), node_begin_.end(), front_ + i);
    run_count_[static_cast<std::size_t>(after - node_begin_.begin()) - 1] = kStaleRuns;
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
    const double t_state = filter.state(filter.nodes() - 1).t;
    // One slot more than the rejected returns: splitReturns writes a return it takes one by one
    // to both outputs and advances the one it belongs to.
    r.rejected.assign(size() - accepted_ + 1, MapPoint{});
    // Node by node: its returns mapped in place (as arrays), then copied out as MapPoints, the
    // accepted ones into the buffer's front (the write position never passes the node's own
    // part), the others into r.rejected.
    std::vector<float> part;
    std::size_t kept = 0, dropped = 0;
    MapPoint* rejected = r.rejected.data();
    for (std::size_t k = 0; k + 1 < node_begin_.size(); ++k) {
      const std::size_t b = node_begin_[k], n = node_begin_[k + 1] - b;
      if (n == 0) continue;
      const FilterState& x = filter.state(k);
      const Vec3 omega = imu[k_first + filter.nodeSample(k)].gyro - x.b_g;
      const Vec3 v_b = x.R_wb.transpose() * x.v_w;
      const Eigen::Matrix3f A = (x.R_wb * ext.R_bl).cast<float>();
      const Eigen::Matrix3f B = (x.R_wb * skew(omega) * ext.R_bl).cast<float>();
      const Eigen::Vector3f a = (x.R_wb * ext.p_bl + x.p_w).cast<float>();
      const Eigen::Vector3f bv = (x.R_wb * (omega.cross(ext.p_bl) + v_b)).cast<float>();
      recorder_kernels::NodeMap m;
      for (int row = 0; row < 3; ++row) {
        for (int col = 0; col < 3; ++col) {
          m.A[3 * row + col] = A(row, col);
          m.B[3 * row + col] = B(row, col);
        }
        m.a[row] = a(row);
        m.b[row] = bv(row);
      }
      m.time = static_cast<float>(x.t - t_state);
      float* f = reinterpret_cast<float*>(returns_.data()) + 7 * b;
      recorder_kernels::mapReturns(n, m, f, f + n, f + 2 * n, f + 5 * n);
      // The node's part is copied aside only if the MapPoints written may reach it: they end
      // before it once the unused slots in front and the returns rejected so far outnumber the
      // node's (b = front + those written + those rejected).
      const float* src = f;
      if (kept + n > b) {
        part.assign(f, f + 7 * n);
        src = part.data();
      }
      kept += recorder_kernels::splitReturns(n, src, cells_.data() + (b - front_), kNoCell,
                                             returns_.data() + kept, rejected + dropped, dropped);
    }
    r.rejected.resize(dropped);
    returns_.resize(kept);
    r.static_map = std::move(returns_);
    returns_ = {};
    cells_ = {};
    runs_ = {};
    run_begin_ = {0};
    run_count_.clear();
    run_inv_h_.clear();
    node_begin_ = {0};
    front_ = 0;
    end_ = 0;
    accepted_ = 0;
  }

 private:
  struct Run {
    const DopplerPoint* points;
    std::size_t count, step;
    double stamp, t_node;
  };
  /// v holds at least n elements: beyond the room reserve() made, half as many again each time
  /// (so that a window longer than foreseen is copied a few times, not at every node).
  template <class T>
  static void holdAtLeast(std::vector<T>& v, std::size_t n) {
    if (v.size() < n) v.resize(std::max(n, v.size() + v.size() / 2));
  }
  /// The runs of a node's n returns (cells, its arrays from f) into runs_ from `first`.
  std::size_t makeRuns(std::size_t n, const std::uint16_t* cell, float inv_h, const float* f,
                       std::size_t first) {
    if (run_terms_.size() < 9 * n) run_terms_.resize(9 * n);
    recorder_kernels::runTerms(n, inv_h, f, f + n, f + 2 * n, f + 5 * n, run_terms_.data());
    return recorder_kernels::cellRuns(n, cell, kNoCell, run_terms_.data(), f + 4 * n,
                                      runs_.data() + first);
  }
  // The buffers seen as floats: a MapPoint is seven floats.
  static_assert(sizeof(MapPoint) == 7 * sizeof(float) && alignof(MapPoint) == alignof(float));

  std::vector<MapPoint> returns_;     ///< the judged nodes' returns (see the class comment)
  std::vector<std::uint16_t> cells_;  ///< every judged return's cell, kNoCell if not accepted
  std::vector<std::size_t> node_begin_{
      0};                     ///< node k's returns: [node_begin_[k], node_begin_[k+1])
  std::size_t accepted_ = 0;  ///< judged returns accepted (not kNoCell)
  std::size_t front_ = 0;     ///< unused slots before the first node's part (reserve)
  std::size_t end_ = 0;       ///< the end of the laid-out returns in returns_ (the rest is room)
  /// Node k's runs: from runs_[run_begin_[k]], run_count_[k] of them (kStaleRuns: returns were
  /// rejected since they were made; never more than before), made at the time scale
  /// run_inv_h_[k].
  std::vector<recorder_kernels::CellRun> runs_;
  std::vector<std::size_t> run_begin_{0}, run_count_;
  std::vector<float> run_inv_h_;
  std::vector<float> run_terms_;  ///< makeRuns' work space
  static constexpr std::size_t kStaleRuns = static_cast<std::size_t>(-1);
  std::vector<Run> open_runs_;         ///< the open node's returns, where the frames hold them
  std::size_t open_given_ = 0;         ///< returns in open_runs_
  std::vector<std::uint8_t> verdict_;  ///< closeNode's work space: each return usable or not
};

}  // namespace freeinit::detail
