#include "imu_screen.h"

#include <algorithm>
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

void ImuScreen::advance(const std::vector<ImuSample>& raw, bool finished) {
  for (std::size_t i = work_.size(); i < raw.size(); ++i) work_.push_back(raw[i]);
  if (h_ == 0 && (work_.size() > kIntervals || (finished && work_.size() >= 2))) {
    const std::size_t n = std::min(kIntervals, work_.size() - 1);
    std::vector<double> dt(n);
    for (std::size_t i = 0; i < n; ++i) dt[i] = work_[i + 1].t - work_[i].t;
    std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(n / 2), dt.end());
    h_ = dt[n / 2];
  }
  if (h_ == 0 && !finished) return;
  if (recent_g_.empty()) {
    recent_g_.assign(3 * kRecentSamples, 0.0);
    recent_a_.assign(3 * kRecentSamples, 0.0);
  }
  while (next_ < work_.size() && (finished || next_ + 2 < work_.size())) {
    decide(next_);
    if (next_ + 1 < work_.size()) bridge(next_);
    ++next_;
  }
}

void ImuScreen::decide(std::size_t j) {
  const std::size_t n = work_.size();
  const bool neighbours =
      j >= 2 && j + 2 < n && (h_ <= 0 || work_[j + 2].t - work_[j - 2].t <= kNeighbourSpan * h_);
  ImuNoiseScale scale;
  for (const bool accel : {false, true}) {
    const double range = accel ? p_.accel_range : p_.gyro_range;
    const double sigma = accel ? p_.accel_sigma : p_.gyro_sigma;
    const Vec3 y = channel(work_[j], accel);
    const bool out_of_range = !(y.cwiseAbs().maxCoeff() < range);
    // The robust scale (a median over the recent residuals, the most of a sample's cost) only
    // where it decides: it is never below its floor (robustSigma), so residuals within the
    // threshold at the floor are no fault whatever it is.
    double s = 0;
    bool scaled = false;
    auto scale_now = [&]() {
      if (!scaled) s = robustSigma(accel);
      scaled = true;
      return s;
    };
    bool fault = out_of_range;
    Vec3 fit = Vec3::Zero();
    if (neighbours) {
      const double t[4] = {work_[j - 2].t, work_[j - 1].t, work_[j + 1].t, work_[j + 2].t};
      const Vec3* const v[4] = {&channel(work_[j - 2], accel), &channel(work_[j - 1], accel),
                                &channel(work_[j + 1], accel), &channel(work_[j + 2], accel)};
      fit = lagrange(t, v, work_[j].t);
      const Vec3 r = y - fit;
      // Linear extrapolations from each side.
      const Vec3 left = *v[1] + (*v[1] - *v[0]) * ((work_[j].t - t[1]) / (t[1] - t[0]));
      const Vec3 right = *v[2] + (*v[2] - *v[3]) * ((t[2] - work_[j].t) / (t[3] - t[2]));
      const Vec3 el = y - left, er = y - right;
      const double floor_threshold =
          p_.fault_sigmas * (1.4 * sigma) + (accel ? kAccelFloor : kGyroFloor);
      const double threshold =
          r.cwiseAbs().maxCoeff() > floor_threshold
              ? p_.fault_sigmas * scale_now() + (accel ? kAccelFloor : kGyroFloor)
              : floor_threshold;
      for (int a = 0; a < 3 && !fault; ++a)
        fault = std::abs(r(a)) > threshold && std::abs(el(a)) > 0.5 * threshold &&
                std::abs(er(a)) > 0.5 * threshold && el(a) * r(a) > 0 && er(a) * r(a) > 0;
      if (!fault) {
        std::vector<double>& ring = accel ? recent_a_ : recent_g_;
        const std::size_t slot = 3 * (recent_n_ % kRecentSamples);
        for (int a = 0; a < 3; ++a) ring[slot + static_cast<std::size_t>(a)] = std::abs(r(a));
      }
    } else if (fault) {
      // At the stream's ends or next to a gap: the nearest screened value.
      fit = !out_.empty() ? channel(out_.back(), accel)
                          : (j + 1 < n ? channel(work_[j + 1], accel) : Vec3::Zero());
    }
    if (!fault) continue;
    ImuFault f;
    f.t = work_[j].t;
    f.accel = accel;
    f.magnitude = (y - fit).norm();
    f.out_of_range = out_of_range;
    faults_.push_back(f);
    channel(work_[j], accel) = fit;
    const double sf = scale_now();
    const float k =
        static_cast<float>(std::sqrt(kResidualVariance * sf * sf + sigma * sigma) / sigma);
    (accel ? scale.accel : scale.gyro) = k;
  }
  if (neighbours) ++recent_n_;
  out_.push_back(work_[j]);
  scale_.push_back(scale);
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
  // Linear between the samples on each side (a cubic through two noisy pairs a gap apart
  // extrapolates their noise into the gap); what the motion does in between is in the noise.
  const double qg = (b.gyro - a.gyro).norm() / T + kGyroRateChange;
  const double qa = (b.accel - a.accel).norm() / T + kAccelRateChange;
  for (long i = 1; i < steps; ++i) {
    const double u = static_cast<double>(i) / static_cast<double>(steps);
    ImuSample s;
    s.t = a.t + u * T;
    s.gyro = (1 - u) * a.gyro + u * b.gyro;
    s.accel = (1 - u) * a.accel + u * b.accel;
    const double d = std::min(u, 1 - u) * T;
    ImuNoiseScale sc;
    sc.gyro = static_cast<float>(std::sqrt(p_.gyro_sigma * p_.gyro_sigma + qg * qg * d * d) /
                                 p_.gyro_sigma);
    sc.accel = static_cast<float>(std::sqrt(p_.accel_sigma * p_.accel_sigma + qa * qa * d * d) /
                                  p_.accel_sigma);
    out_.push_back(s);
    scale_.push_back(sc);
  }
}

}  // namespace freeinit::detail
