// Which returns the estimators use (finite, within the configured ranges) and the automatic point
// stride, shared by both estimators (joint/, paper/) and the Doppler-inertial odometry.
#pragma once

#include <freeinit/config.h>
#include <freeinit/types.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace freeinit::detail {

/// A point the estimators can use: finite, with a range inside [doppler] [min_range, max_range].
/// The definition; the per-return loops use UsablePoints, which decides the same without a root.
inline bool usablePoint(const DopplerPoint& p, const DopplerParams& dp) {
  if (!p.p_l.allFinite() || !std::isfinite(p.doppler) || !std::isfinite(p.time_offset))
    return false;
  const double r = p.p_l.norm();
  return r > 0 && r >= dp.min_range && r <= dp.max_range;
}

/// usablePoint() on the squared range: the range limits become limits on the float squared
/// range (the one whose root usablePoint() compares), found once by bisection over the floats so
/// that every point gets the same verdict, at the limits too.
class UsablePoints {
 public:
  explicit UsablePoints(const DopplerParams& dp) {
    // The root is monotone in the squared range: each test holds on one end of the floats
    // [0, inf] (the squared range of finite coordinates may overflow to inf).
    const double lo = dp.min_range, hi = dp.max_range;
    lo2_ = firstPassing([lo](float r2) {
      const float r = std::sqrt(r2);
      return r > 0 && r >= lo;
    });
    const float past = firstPassing([hi](float r2) { return !(std::sqrt(r2) <= hi); });
    if (std::isnan(past))
      hi2_ = kInf;  // no range too far
    else if (past > 0)
      hi2_ = std::nextafter(past, 0.0f);
    finite_limit_ = hi2_ < kInf;
  }
  bool operator()(const DopplerPoint& p) const {
    const float x = p.p_l.x(), y = p.p_l.y(), z = p.p_l.z();
    // A squared range within a finite limit has finite coordinates (with an infinity or a NaN
    // among them it is inf or NaN): they need the test only without one. Bit tests and
    // comparisons joined with & (no branch), so that the loops that call it vectorize.
    const unsigned all_finite =
        finite(p.doppler) & finite(p.time_offset) &
        (static_cast<unsigned>(finite_limit_) | (finite(x) & finite(y) & finite(z)));
    const float r2 = p.p_l.squaredNorm();
    return (all_finite & static_cast<unsigned>(r2 >= lo2_) & static_cast<unsigned>(r2 <= hi2_)) !=
           0;
  }

 private:
  static constexpr float kInf = std::numeric_limits<float>::infinity();
  static constexpr float kNone = std::numeric_limits<float>::quiet_NaN();  ///< nothing passes
  /// 1 if v is finite (its exponent bits are not all ones: no floating-point operation), else 0.
  static unsigned finite(float v) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    return (bits & 0x7f800000u) != 0x7f800000u ? 1u : 0u;
  }
  /// The smallest float in [0, inf] at which `pass` holds (false below it, true from it on),
  /// NaN if it holds nowhere.
  template <class Pass>
  static float firstPassing(Pass pass) {
    auto value = [](std::uint32_t bits) {
      float f;
      std::memcpy(&f, &bits, sizeof f);
      return f;
    };
    std::uint32_t a = 0, b = 0x7f800000u;  // the bits of +0 and +inf: ordered as the floats
    if (!pass(value(b))) return kNone;
    while (a < b) {
      const std::uint32_t mid = a + (b - a) / 2;
      if (pass(value(mid)))
        b = mid;
      else
        a = mid + 1;
    }
    return value(a);
  }
  float lo2_ = kNone, hi2_ = kNone;  ///< a usable squared range is in [lo2_, hi2_]
  bool finite_limit_ = false;        ///< hi2_ is finite
};

/// The point stride that brings the point rate of the first frame with a measurable span closest
/// to max_point_rate (1 when no frame tells the rate). `Frames`: a sequence of items with a
/// `points` vector.
template <class Frames>
int automaticPointStride(const Frames& frames, double max_point_rate) {
  for (const auto& f : frames) {
    if (f.points.size() < 2) continue;
    const double span = f.points.back().time_offset - f.points.front().time_offset;
    if (!(span > 0)) continue;
    const double rate = static_cast<double>(f.points.size()) / span;
    return std::max(1, static_cast<int>(std::lround(rate / max_point_rate)));
  }
  return 1;
}

}  // namespace freeinit::detail
