#include "imu_screen.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace freeinit::detail {
namespace {

constexpr std::size_t kRecentSamples = 40;  ///< the robust scale's span
constexpr std::size_t kIntervals = 20;      ///< the nominal interval's span
constexpr double kGapIntervals = 2.5;       ///< an interval beyond this many nominal ones: a gap
/// The neighbours test needs its four samples within this many nominal intervals (else, next to
/// a gap, only the range is tested).
constexpr double kNeighbourSpan = 6.0;
/// Variance of the residual against the cubic through four neighbours, in units of the
/// per-sample variance, at equal spacing: 1 + (1 + 16 + 16 + 1) / 36.
constexpr double kResidualVariance = 1.94;
constexpr double kGyroFloor = 0.05;        ///< [rad/s] the neighbours test's physical floor
constexpr double kAccelFloor = 0.5;        ///< [m/s^2]
constexpr double kGyroRateChange = 1.0;    ///< [rad/s^2] within a bridged gap, beyond the trend
constexpr double kAccelRateChange = 10.0;  ///< [m/s^3]

Vec3& channel(ImuSample& s, bool accel) { return accel ? s.accel : s.gyro; }
/// A component at or beyond the range (NaN included).
bool outOfRange(const Vec3& y, double range) { return !(y.cwiseAbs().maxCoeff() < range); }

/// The value at t of the Lagrange polynomial through (t_i, y_i), i = 0..3.
Vec3 lagrange(const double (&t)[4], const Vec3* const (&y)[4], double at) {
  Vec3 v = Vec3::Zero();
  for (int i = 0; i < 4; ++i) {
    double w = 1.0;
    for (int m = 0; m < 4; ++m)
      if (m != i) w *= (at - t[m]) / (t[i] - t[m]);
    v += w * *y[i];
  }
  return v;
}

}  // namespace

double ImuScreen::robustSigma(bool accel) const {
  const double sigma = accel ? p_.accel_sigma : p_.gyro_sigma;
  const double floor = 1.4 * sigma;
  const std::vector<double>& ring = accel ? recent_a_ : recent_g_;
  const std::size_t n = std::min(recent_n_, kRecentSamples) * 3;
  if (n < 15) return floor;
  std::vector<double>& v = scratch_;  // no allocation per sample
  v.assign(ring.begin(), ring.begin() + static_cast<std::ptrdiff_t>(n));
  auto mid = v.begin() + static_cast<std::ptrdiff_t>(n / 2);
  std::nth_element(v.begin(), mid, v.end());
  return std::max(floor, 1.4826 * *mid);
}

double ImuScreen::localInterval(std::size_t j) const {
  // Intervals ending at most kMaxRun + 2 samples after j: what a live stream has received when
  // j is decided, so that live and offline screening agree. The median of the kIntervals ending
  // there, or of the few ahead of j when larger: after a burst (a driver stamping on receipt)
  // the steady intervals ahead are the stream's, though the burst still fills the span behind.
  const std::size_t last = work_.size() - 1;  // intervals end at samples 1..last
  if (last == 0) return 0.0;
  const std::size_t hi = std::min(last, std::max(j + kMaxRun + 2, kIntervals));
  auto median = [this](std::size_t from, std::size_t to) {
    std::array<double, kIntervals> dt{};
    std::size_t n = 0;
    for (std::size_t i = from; i <= to; ++i) dt[n++] = work_[i].t - work_[i - 1].t;
    std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(n / 2),
                     dt.begin() + static_cast<std::ptrdiff_t>(n));
    return dt[n / 2];
  };
  const double behind = median(hi > kIntervals ? hi - kIntervals + 1 : 1, hi);
  const std::size_t ahead_hi = std::min(last, j + kMaxRun + 2);
  return ahead_hi > j ? std::max(behind, median(j + 1, ahead_hi)) : behind;
}

void ImuScreen::advance(const std::vector<ImuSample>& raw, bool finished) {
  for (std::size_t i = work_.size(); i < raw.size(); ++i) work_.push_back(raw[i]);
  if (work_.size() <= kIntervals && !(finished && work_.size() >= 2)) return;
  if (recent_g_.empty()) {
    recent_g_.assign(3 * kRecentSamples, 0.0);
    recent_a_.assign(3 * kRecentSamples, 0.0);
  }
  while (next_ < work_.size() && (finished || next_ + kMaxRun + 2 < work_.size())) {
    h_ = localInterval(next_);
    decide(next_);
    if (next_ + 1 < work_.size()) bridge(next_);
    ++next_;
  }
}

void ImuScreen::decide(std::size_t j) {
  const std::size_t n = work_.size();
  const bool neighbours =
      j >= 2 && j + 2 < n && (h_ <= 0 || work_[j + 2].t - work_[j - 2].t <= kNeighbourSpan * h_);
  ImuExtraNoise extra;
  for (const bool accel : {false, true}) {
    Vec3 fit = Vec3::Zero();
    double var = 0;
    if (!screenSensor(j, accel, neighbours, fit, var)) {
      t_measured_[accel ? 1 : 0] = work_[j].t;
      measured_[accel ? 1 : 0] = true;
      continue;
    }
    const Vec3 y = channel(work_[j], accel);
    ImuFault f;
    f.t = work_[j].t;
    f.accel = accel;
    f.magnitude = (y - fit).norm();
    f.out_of_range = outOfRange(y, accel ? p_.accel_range : p_.gyro_range);
    faults_.push_back(f);
    channel(work_[j], accel) = fit;
    (accel ? extra.accel : extra.gyro) = static_cast<float>(var);
    (accel ? extra.accel_synthetic : extra.gyro_synthetic) = true;
  }
  if (neighbours) ++recent_n_;
  out_.push_back(work_[j]);
  extra_.push_back(extra);
  for (const int k : {0, 1}) {
    left_var_[k][1] = left_var_[k][0];
    left_var_[k][0] = k == 1 ? extra.accel : extra.gyro;
  }
}

bool ImuScreen::screenSensor(std::size_t j, bool accel, bool neighbours, Vec3& fit,
                             double& extra_var) {
  const std::size_t n = work_.size();
  const double range = accel ? p_.accel_range : p_.gyro_range;
  const double sigma = accel ? p_.accel_sigma : p_.gyro_sigma;
  const double floor = accel ? kAccelFloor : kGyroFloor;
  const Vec3 y = channel(work_[j], accel);
  const bool out_of_range = outOfRange(y, range);
  const std::vector<ImuSample>& w = work_;
  auto value = [&](std::size_t i) -> const Vec3& { return channel(work_[i], accel); };
  auto in_range = [&](std::size_t i) { return !outOfRange(value(i), range); };
  // The right pair (a, b) is clean: a is met by the cubic through j-2, j-1, b, b+1 (b + 1 in
  // range and no gap away; else nothing to tell). A faulty a, or a b or b + 1 that is one, make
  // it miss. An interpolation, not an extrapolation: its noise (1.4 sigma) and the motion it
  // misses (3 to 10 times the lone test's) stay within the threshold where linear
  // extrapolations from one side miss a vibrating platform by many times it.
  auto pair_clean = [&](std::size_t a, std::size_t b, double threshold) {
    const std::size_t c = b + 1;
    if (j < 2 || c >= n || !in_range(c) || (h_ > 0 && w[c].t - w[b].t > kGapIntervals * h_))
      return true;
    const double t[4] = {w[j - 2].t, w[j - 1].t, w[b].t, w[c].t};
    const Vec3* const v[4] = {&value(j - 2), &value(j - 1), &value(b), &value(c)};
    return (value(a) - lagrange(t, v, w[a].t)).cwiseAbs().maxCoeff() <= threshold;
  };

  // The lone-sample test's residual.
  Vec3 r1 = Vec3::Zero();
  bool lone_nodes = false;  // its right pair in range
  if (neighbours) {
    const double t[4] = {w[j - 2].t, w[j - 1].t, w[j + 1].t, w[j + 2].t};
    const Vec3* const v[4] = {&value(j - 2), &value(j - 1), &value(j + 1), &value(j + 2)};
    r1 = y - lagrange(t, v, w[j].t);
    lone_nodes = in_range(j + 1) && in_range(j + 2);
  }
  auto record = [&](const Vec3& r) {
    std::vector<double>& ring = accel ? recent_a_ : recent_g_;
    const std::size_t slot = 3 * (recent_n_ % kRecentSamples);
    for (int a = 0; a < 3; ++a) ring[slot + static_cast<std::size_t>(a)] = std::abs(r(a));
  };
  // Within the smallest threshold robustSigma() can give: no fault, no need of the sigma.
  const double least = p_.fault_sigmas * (1.4 * sigma) + floor;
  if (!out_of_range && (!neighbours || !(r1.cwiseAbs().maxCoeff() > least))) {
    if (neighbours) record(r1);
    return false;
  }

  const double s = robustSigma(accel);
  const double threshold = p_.fault_sigmas * s + floor;
  if (j >= 2) {
    for (std::size_t L = 1; L <= kMaxRun; ++L) {
      const std::size_t ra = j + L, rb = j + L + 1;
      if (rb >= n) break;
      if (h_ > 0 && w[rb].t - w[j - 2].t > (kNeighbourSpan + static_cast<double>(L - 1)) * h_)
        break;
      if (!in_range(ra) || !in_range(rb) || !pair_clean(ra, rb, threshold)) continue;
      const double t[4] = {w[j - 2].t, w[j - 1].t, w[ra].t, w[rb].t};
      const Vec3* const v[4] = {&value(j - 2), &value(j - 1), &value(ra), &value(rb)};
      // Each sample of the run against the cubic and the linear extrapolations from each side.
      bool run = true;
      for (std::size_t i = j; i < ra && run; ++i) {
        if (outOfRange(value(i), range)) continue;
        const double ti = w[i].t;
        const Vec3 r = value(i) - lagrange(t, v, ti);
        const Vec3 left = *v[1] + (*v[1] - *v[0]) * ((ti - t[1]) / (t[1] - t[0]));
        const Vec3 right = *v[2] + (*v[2] - *v[3]) * ((t[2] - ti) / (t[3] - t[2]));
        const Vec3 el = value(i) - left, er = value(i) - right;
        bool spike = false;
        for (int a = 0; a < 3 && !spike; ++a)
          spike = std::abs(r(a)) > threshold && std::abs(el(a)) > 0.5 * threshold &&
                  std::abs(er(a)) > 0.5 * threshold && el(a) * r(a) > 0 && er(a) * r(a) > 0;
        run = spike;
      }
      if (!run) continue;
      fit = lagrange(t, v, w[j].t);
      // The interpolation's error: the nodes' noise (and a replaced left node's own error), and
      // the motion the cubic misses.
      double weights = 0, left = 0, poly = 1;
      for (int i = 0; i < 4; ++i) {
        double wi = 1.0;
        for (int m = 0; m < 4; ++m)
          if (m != i) wi *= (w[j].t - t[m]) / (t[i] - t[m]);
        weights += wi * wi;
        if (i < 2) left += wi * wi * left_var_[accel ? 1 : 0][1 - i];
        poly *= w[j].t - t[i];
      }
      const double motion = std::max(0.0, s * s - kResidualVariance * sigma * sigma);
      const double ratio = h_ > 0 ? poly / (4.0 * h_ * h_ * h_ * h_) : 1.0;
      extra_var = sigma * sigma * weights + left + motion * ratio * ratio;
      return true;
    }
  }
  if (!out_of_range) {
    // Not a fault: its residual joins the scale's span unless a faulty neighbour made it.
    if (neighbours && lone_nodes && pair_clean(j + 1, j + 2, threshold)) record(r1);
    return false;
  }
  // Out of range with no cubic to replace it: the nearest screened value, held.
  double t_held = w[j].t;
  if (!out_.empty()) {
    fit = channel(out_.back(), accel);
  } else {
    std::size_t i = j + 1;
    while (i < n && !in_range(i)) ++i;
    if (i < n) {
      fit = value(i);
      t_held = w[i].t;
    }
  }
  // Its error grows with the time d since the sensor's last measurement at the rate of change
  // before it (a vibrating platform's) plus the gaps' allowance.
  const int k = accel ? 1 : 0;
  if (j >= 2 && w[j - 1].t > w[j - 2].t && left_var_[k][0] == 0 && left_var_[k][1] == 0)
    hold_rate_[k] = (value(j - 1) - value(j - 2)).cwiseAbs().maxCoeff() / (w[j - 1].t - w[j - 2].t);
  const double q = (accel ? kAccelRateChange : kGyroRateChange) + hold_rate_[k];
  const double d = std::abs(w[j].t - (measured_[k] ? t_measured_[k] : t_held));
  extra_var = s * s + q * q * d * d;
  return true;
}

void ImuScreen::bridge(std::size_t j) {
  if (!(h_ > 0)) return;
  const ImuSample& a = work_[j];
  const ImuSample& b = work_[j + 1];
  const double T = b.t - a.t;
  if (!(T > kGapIntervals * h_)) return;
  ImuGap g;
  g.t = a.t;
  g.length = T;
  const long steps = std::max(2L, std::lround(T / h_));
  g.missing = static_cast<std::size_t>(steps - 1);
  g.bridged = T <= p_.max_bridged_gap;
  gaps_.push_back(g);
  if (!g.bridged) return;
  // On the line between the samples on each side (see the class comment); what the motion does
  // in between is in the extra variance.
  const double qg = (b.gyro - a.gyro).norm() / T + kGyroRateChange;
  const double qa = (b.accel - a.accel).norm() / T + kAccelRateChange;
  for (long i = 1; i < steps; ++i) {
    const double u = static_cast<double>(i) / static_cast<double>(steps);
    ImuSample s;
    s.t = a.t + u * T;
    s.gyro = (1 - u) * a.gyro + u * b.gyro;
    s.accel = (1 - u) * a.accel + u * b.accel;
    const double d = std::min(u, 1 - u) * T;
    ImuExtraNoise e;
    e.gyro = static_cast<float>(qg * qg * d * d);
    e.accel = static_cast<float>(qa * qa * d * d);
    e.gyro_synthetic = e.accel_synthetic = true;
    out_.push_back(s);
    extra_.push_back(e);
  }
}

}  // namespace freeinit::detail
