// The window recorder's vectorized per-return loops (window_parts.h) against the scalar forms they
// replace: a node's returns laid out and tested (usablePoint), the rest cells of RestCells::cellOf,
// the map of a return (A p_l + a + tau (B p_l + b)), the split of a node's returns into the map and
// the rejected ones, and the runs of the moving-cell test against the residuals they sum.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "joint/window_parts.h"

namespace freeinit::detail {
namespace {

struct Returns {
  std::vector<float> x, y, z, tau, doppler;
};

/// Random returns up to 150 m, and returns at each range bin's edge (the float nearest it and
/// its neighbours), on the axes, in every octant.
Returns someReturns() {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> c(-150.0f, 150.0f), t(-0.0025f, 0.0025f), d(-5, 5);
  Returns r;
  auto add = [&](const Eigen::Vector3f& p) {
    r.x.push_back(p.x());
    r.y.push_back(p.y());
    r.z.push_back(p.z());
    r.tau.push_back(t(rng));
    r.doppler.push_back(d(rng));
  };
  for (int i = 0; i < 20000; ++i) add(Eigen::Vector3f(c(rng), c(rng), c(rng)) * (i % 3 + 1) / 3.0f);
  for (const float e2 : RestCells::kRangeEdges2) {
    const Eigen::Vector3f dir = Eigen::Vector3f(c(rng), c(rng), c(rng)).normalized();
    float r0 = std::sqrt(e2);
    for (int k = 0; k < 3; ++k) r0 = std::nextafter(r0, 0.0f);
    for (int k = 0; k < 7; ++k, r0 = std::nextafter(r0, 1e9f)) {
      add(dir * r0);
      add(Eigen::Vector3f(r0, 0, 0));
      add(Eigen::Vector3f(0, -r0, 0));
    }
  }
  for (const float sx : {-1.0f, 1.0f})
    for (const float sy : {-1.0f, 1.0f})
      for (const float sz : {-1.0f, 0.0f, 1.0f}) add(Eigen::Vector3f(3 * sx, 2 * sy, 5 * sz));
  return r;
}

TEST(WindowParts, LayOutCopiesAndTestsEachReturn) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> c(-200.0f, 200.0f), t(0.0f, 0.1f);
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const float odd[] = {kInf, -kInf, std::numeric_limits<float>::quiet_NaN(), 0.0f, 1e30f};
  std::vector<DopplerPoint> frame(1000);
  for (std::size_t i = 0; i < frame.size(); ++i) {
    DopplerPoint& p = frame[i];
    p.p_l = Eigen::Vector3f(c(rng), c(rng), c(rng)) * (i % 7 == 0 ? 0.001f : 1.0f);
    p.doppler = c(rng);
    p.time_offset = t(rng);
    p.intensity = c(rng);
    p.line = static_cast<std::uint16_t>(i);
    if (i % 13 == 0) p.p_l[static_cast<int>(i % 3)] = odd[i % 5];  // non-finite coordinates
    if (i % 17 == 0) p.doppler = odd[i % 5];
    if (i % 19 == 0) p.time_offset = odd[(i + 1) % 5];
  }
  for (const double max_range : {150.0, std::numeric_limits<double>::infinity()}) {
    DopplerParams vp;
    vp.min_range = 0.5;
    vp.max_range = max_range;
    const UsablePoints usable(vp);
    const double stamp = 1.7e9, t_node = 1.7e9 + 0.05;
    // Runs of every length around the block of four, from the frame's start or its middle,
    // consecutive or strided.
    for (const std::size_t step : {1, 3})
      for (const std::size_t count : {0, 1, 4, 5, 8, 9, 250})
        for (const std::size_t first : {0, 101}) {
          std::vector<float> a(6 * count);
          std::vector<std::uint8_t> u(count);
          float *x = a.data(), *y = x + count, *z = y + count, *in = z + count, *d = in + count,
                *tau = d + count;
          const std::size_t n =
              recorder_kernels::layOut(frame.data() + first, count, step, stamp, t_node, usable, x,
                                       y, z, in, d, tau, u.data());
          std::size_t passed = 0;
          for (std::size_t i = 0; i < count; ++i) {
            const DopplerPoint& p = frame[first + i * step];
            const bool usable_point = usablePoint(p, vp);
            passed += usable_point ? 1 : 0;
            ASSERT_EQ(u[i], usable_point ? 1 : 0) << step << " " << count << " " << i;
            // Bits, not values: a NaN copied is a NaN.
            const float fields[] = {p.p_l.x(), p.p_l.y(), p.p_l.z(), p.intensity, p.doppler};
            const float* arrays[] = {x, y, z, in, d};
            for (int k = 0; k < 5; ++k)
              ASSERT_EQ(std::memcmp(&arrays[k][i], &fields[k], sizeof(float)), 0) << k << " " << i;
            const float tau_i =
                static_cast<float>(stamp + static_cast<double>(p.time_offset) - t_node);
            ASSERT_EQ(std::memcmp(&tau[i], &tau_i, sizeof(float)), 0) << i;
          }
          EXPECT_EQ(n, passed);
        }
  }
}

TEST(WindowParts, CellsAreThoseOfRestCells) {
  const Returns r = someReturns();
  const std::size_t n = r.x.size();
  std::vector<std::uint16_t> cells(n);
  recorder_kernels::cellsOf(n, r.x.data(), r.y.data(), r.z.data(), cells.data());
  for (std::size_t i = 0; i < n; ++i)
    ASSERT_EQ(cells[i], RestCells::cellOf(Eigen::Vector3f(r.x[i], r.y[i], r.z[i])))
        << "return " << i << " at " << r.x[i] << " " << r.y[i] << " " << r.z[i];
}

TEST(WindowParts, ReturnsMapThroughTheNodeMotion) {
  Returns r = someReturns();
  const std::size_t n = r.x.size();
  const Eigen::Matrix3d A = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).matrix();
  const Eigen::Matrix3d B = A * 0.3;
  const Eigen::Vector3d a(0.5, -1.0, 2.0), b(1.2, 0.1, -0.3);
  recorder_kernels::NodeMap m;
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) {
      m.A[3 * row + col] = static_cast<float>(A(row, col));
      m.B[3 * row + col] = static_cast<float>(B(row, col));
    }
    m.a[row] = static_cast<float>(a(row));
    m.b[row] = static_cast<float>(b(row));
  }
  m.time = -0.2f;
  const Returns before = r;
  recorder_kernels::mapReturns(n, m, r.x.data(), r.y.data(), r.z.data(), r.tau.data());
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p(before.x[i], before.y[i], before.z[i]);
    const double tau = before.tau[i];
    const Eigen::Vector3d w = A * p + a + tau * (B * p + b);
    // Float rounding of 7-digit products at up to 150 m.
    EXPECT_NEAR(r.x[i], w.x(), 1e-4) << i;
    EXPECT_NEAR(r.y[i], w.y(), 1e-4) << i;
    EXPECT_NEAR(r.z[i], w.z(), 1e-4) << i;
    EXPECT_EQ(r.tau[i], -0.2f + before.tau[i]) << i;
  }
}

TEST(WindowParts, SplitReturnsCopiesEachReturnToItsList) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> v(-100, 100);
  // Runs of accepted returns of every length (the blocks of four and the ones around them),
  // scattered rejected ones, and node sizes around the block size.
  for (const std::size_t n : {0, 1, 3, 4, 5, 8, 9, 61, 1000}) {
    std::vector<float> arrays(7 * n);
    for (float& a : arrays) a = v(rng);
    std::vector<std::uint16_t> cell(n);
    std::bernoulli_distribution rejected(n % 2 == 0 ? 0.05 : 0.5);
    for (std::size_t j = 0; j < n; ++j) cell[j] = rejected(rng) ? 7 : static_cast<std::uint16_t>(j);
    std::vector<MapPoint> map(n), rejected_out(n + 1);
    std::size_t dropped = 2;  // added to
    const std::size_t kept = recorder_kernels::splitReturns(
        n, arrays.data(), cell.data(), 7, map.data(), rejected_out.data(), dropped);
    std::size_t k = 0, r = 0;
    for (std::size_t j = 0; j < n; ++j) {
      const MapPoint& p = cell[j] != 7 ? map[k++] : rejected_out[r++];
      EXPECT_EQ(p.p_w.x(), arrays[j]) << n << " " << j;
      EXPECT_EQ(p.p_w.y(), arrays[n + j]);
      EXPECT_EQ(p.p_w.z(), arrays[2 * n + j]);
      EXPECT_EQ(p.intensity, arrays[3 * n + j]);
      EXPECT_EQ(p.doppler, arrays[4 * n + j]);
      EXPECT_EQ(p.time, arrays[5 * n + j]);
      EXPECT_EQ(p.residual, arrays[6 * n + j]);
    }
    EXPECT_EQ(kept, k);
    EXPECT_EQ(dropped, 2 + r);
  }
}

TEST(WindowParts, ARunsResidualSumIsThatOfItsReturns) {
  const Returns r = someReturns();
  const std::size_t n = r.x.size();
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> cell_of(0, 40), run(1, 30);
  constexpr std::uint16_t kNo = 50;
  // Runs of one cell, with returns in no cell among and between them.
  std::vector<std::uint16_t> cell;
  while (cell.size() < n) {
    const std::uint16_t c = cell_of(rng);
    for (int k = run(rng); k > 0 && cell.size() < n; --k)
      cell.push_back(std::bernoulli_distribution(0.1)(rng) ? kNo : c);
  }
  const float inv_h = 1.0f / 0.0025f;
  std::vector<float> terms(9 * n);
  recorder_kernels::runTerms(n, inv_h, r.x.data(), r.y.data(), r.z.data(), r.tau.data(),
                             terms.data());
  std::vector<recorder_kernels::CellRun> runs(n);
  const std::size_t m =
      recorder_kernels::cellRuns(n, cell.data(), kNo, terms.data(), r.doppler.data(), runs.data());
  const double Q[9] = {1.5, -0.2, 0.03, 0.4, 0.1, -0.05, -0.02, 0.01, 0.003};
  const Eigen::Vector3d q0(Q[0], Q[1], Q[2]), q1(Q[3], Q[4], Q[5]), q2(Q[6], Q[7], Q[8]);
  // The scalar form, return by return in double, run by run: a run ends where the next return
  // in a cell is in another one.
  std::size_t j = 0, in_cells = 0;
  for (std::size_t i = 0; i < m; ++i) {
    const recorder_kernels::CellRun& run_i = runs[i];
    if (i > 0) {
      EXPECT_NE(run_i.cell, runs[i - 1].cell) << "run " << i << " is not maximal";
    }
    double sum = 0, scale = 0;
    std::uint32_t count = 0;
    for (; j < n && count < run_i.count; ++j) {
      if (cell[j] == kNo) continue;
      ASSERT_EQ(cell[j], run_i.cell) << "return " << j << ", run " << i;
      const double s = static_cast<double>(r.tau[j] * inv_h);
      const Eigen::Vector3d v = q0 + s * (q1 + s * q2);
      const Eigen::Vector3d p(r.x[j], r.y[j], r.z[j]);
      sum += r.doppler[j] + p.dot(v) / p.norm();
      scale += std::abs(r.doppler[j]) + v.norm();
      ++count;
    }
    ASSERT_EQ(count, run_i.count) << "run " << i;
    in_cells += count;
    // The run's sums are in float: each term rounded a few times (a few 1e-7 of its size), and
    // the sums of up to 30 terms: within 1e-5 of the sum of the terms' sizes.
    EXPECT_NEAR(run_i.residualSum(Q), sum, 1e-5 * scale) << "run " << i;
  }
  for (; j < n; ++j) EXPECT_EQ(cell[j], kNo) << "return " << j << " is in no run";
  EXPECT_EQ(in_cells, static_cast<std::size_t>(std::count_if(
                          cell.begin(), cell.end(), [](std::uint16_t c) { return c != kNo; })));
}

}  // namespace
}  // namespace freeinit::detail
