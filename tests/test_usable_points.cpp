// The per-return usability test on the squared range (UsablePoints) against its definition
// (usablePoint, with the root): the same verdict on every point, at the range limits to the last
// float, for non-finite values and for limits that exclude everything or nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "usable_points.h"

namespace freeinit::detail {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

DopplerPoint pointAt(const Eigen::Vector3f& p_l, float doppler = 0.5f, float time = 0.01f) {
  DopplerPoint p;
  p.p_l = p_l;
  p.doppler = doppler;
  p.time_offset = time;
  return p;
}

/// Points whose range is each float within `steps` of `range` (as float), along three
/// directions (the squared range rounds differently along each).
std::vector<DopplerPoint> pointsAround(double range, int steps) {
  std::vector<DopplerPoint> out;
  const Eigen::Vector3f dirs[] = {Eigen::Vector3f::UnitX(), Eigen::Vector3f(1, 1, 1).normalized(),
                                  Eigen::Vector3f(0.3f, -0.8f, 0.52f).normalized()};
  for (const Eigen::Vector3f& d : dirs) {
    float r = static_cast<float>(range);
    for (int i = 0; i < steps; ++i) r = std::nextafter(r, 0.0f);
    for (int i = 0; i <= 2 * steps; ++i, r = std::nextafter(r, kInf)) {
      out.push_back(pointAt(d * r));
      // The coordinates themselves one float apart: squared ranges between the above.
      Eigen::Vector3f q = d * r;
      q.x() = std::nextafter(q.x(), kInf);
      out.push_back(pointAt(q));
    }
  }
  return out;
}

void expectSameVerdicts(const DopplerParams& vp, const std::vector<DopplerPoint>& pts) {
  const UsablePoints usable(vp);
  for (const DopplerPoint& p : pts)
    ASSERT_EQ(usable(p), usablePoint(p, vp))
        << "range " << p.p_l.norm() << " (" << p.p_l.transpose() << "), limits [" << vp.min_range
        << ", " << vp.max_range << "]";
}

TEST(UsablePoints, SameVerdictAtTheRangeLimits) {
  for (const auto& [lo, hi] : {std::pair{1.0, 150.0}, std::pair{0.3, 80.0}, std::pair{0.0, 1e4},
                               std::pair{1.0 / 3.0, 100.0 / 3.0}, std::pair{2.5, 2.5}}) {
    DopplerParams vp;
    vp.min_range = lo;
    vp.max_range = hi;
    std::vector<DopplerPoint> pts = pointsAround(lo, 64);
    const std::vector<DopplerPoint> far = pointsAround(hi, 64);
    pts.insert(pts.end(), far.begin(), far.end());
    pts.push_back(pointAt(Eigen::Vector3f::Zero()));
    pts.push_back(pointAt(Eigen::Vector3f(1e-30f, 0, 0)));
    pts.push_back(pointAt(Eigen::Vector3f(std::numeric_limits<float>::denorm_min(), 0, 0)));
    expectSameVerdicts(vp, pts);
  }
}

TEST(UsablePoints, SameVerdictOnRandomPoints) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> c(-200.0f, 200.0f);
  std::vector<DopplerPoint> pts;
  for (int i = 0; i < 200000; ++i) pts.push_back(pointAt(Eigen::Vector3f(c(rng), c(rng), c(rng))));
  expectSameVerdicts(DopplerParams{}, pts);
}

TEST(UsablePoints, NonFiniteValuesAreNotUsable) {
  const Eigen::Vector3f p(3, 4, 5);
  std::vector<DopplerPoint> pts = {pointAt(p)};
  for (const float bad : {kInf, -kInf, kNaN}) {
    for (int axis = 0; axis < 3; ++axis) {
      Eigen::Vector3f q = p;
      q(axis) = bad;
      pts.push_back(pointAt(q));
    }
    pts.push_back(pointAt(p, bad));
    pts.push_back(pointAt(p, 0.5f, bad));
  }
  // Finite coordinates whose squared range overflows the float.
  pts.push_back(pointAt(Eigen::Vector3f(3e19f, 0, 0)));
  for (const double hi : {150.0, std::numeric_limits<double>::infinity()}) {
    DopplerParams vp;
    vp.max_range = hi;
    expectSameVerdicts(vp, pts);
    EXPECT_TRUE(UsablePoints(vp)(pts.front()));
    for (std::size_t i = 1; i + 1 < pts.size(); ++i) EXPECT_FALSE(UsablePoints(vp)(pts[i])) << i;
  }
}

TEST(UsablePoints, LimitsThatExcludeEverythingOrNothing) {
  std::vector<DopplerPoint> pts = pointsAround(1.0, 8);
  pts.push_back(pointAt(Eigen::Vector3f::Zero()));
  pts.push_back(pointAt(Eigen::Vector3f(3e19f, 0, 0)));
  pts.push_back(pointAt(Eigen::Vector3f(1e-3f, 0, 0)));
  const double inf = std::numeric_limits<double>::infinity(), nan = std::nan("");
  for (const auto& [lo, hi] : {std::pair{-1.0, inf}, std::pair{0.0, inf}, std::pair{2.0, 1.0},
                               std::pair{nan, 10.0}, std::pair{0.5, nan}, std::pair{inf, inf},
                               std::pair{-inf, -1.0}, std::pair{0.0, 0.0}, std::pair{1e40, 1e41}}) {
    DopplerParams vp;
    vp.min_range = lo;
    vp.max_range = hi;
    expectSameVerdicts(vp, pts);
  }
}

}  // namespace
}  // namespace freeinit::detail
