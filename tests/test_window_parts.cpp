// The window recorder's vectorized per-return loops (window_parts.h) against the scalar forms they
// replace: a node's returns laid out and tested (usablePoint), the rest cells of RestCells::cellOf,
// the Doppler residual as Eigen computes it, the map of a return (A p_l + a + tau (B p_l + b)), the
// split of a node's returns into the map and the rejected ones, and the sums of the moving-cell
// test.
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

TEST(WindowParts, DopplerResidualsAreThoseOfTheScalarForm) {
  const Returns r = someReturns();
  const std::size_t n = r.x.size();
  const float q[9] = {1.5f, -0.2f, 0.03f, 0.4f, 0.1f, -0.05f, -0.02f, 0.01f, 0.003f};
  const float inv_h = 1.0f / 0.0025f;
  std::vector<float> res(n);
  recorder_kernels::dopplerResiduals(n, q, inv_h, r.x.data(), r.y.data(), r.z.data(), r.tau.data(),
                                     r.doppler.data(), res.data());
  const Eigen::Vector3f q0(q[0], q[1], q[2]), q1(q[3], q[4], q[5]), q2(q[6], q[7], q[8]);
  for (std::size_t i = 0; i < n; ++i) {
    const float s = r.tau[i] * inv_h;
    const Eigen::Vector3f v = q0 + s * (q1 + s * q2);
    const Eigen::Vector3f p_l(r.x[i], r.y[i], r.z[i]);
    ASSERT_EQ(res[i], r.doppler[i] + p_l.dot(v) / p_l.norm()) << "return " << i;
  }
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

TEST(WindowParts, SumIntoCellsAddsInOrder) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> v(-0.3f, 0.3f);
  std::uniform_int_distribution<int> cell_of(0, 40), run(1, 12);
  constexpr std::uint16_t kNo = 50;
  std::vector<double> sum(kNo + 1, 0.0), sum_ref(kNo + 1, 0.0);
  std::vector<std::uint32_t> count(kNo + 1, 0), count_ref(kNo + 1, 0), touched(kNo + 2);
  std::vector<std::uint32_t> touched_ref;
  double squares = 0, squares_ref = 0;
  std::size_t slots = 0, in_cells_ref = 0, in_cells = 0;
  // Several calls (nodes) into the same sums: runs of one cell, rejected returns among them.
  for (const std::size_t n : {0, 1, 7, 100, 333}) {
    std::vector<std::uint16_t> cell;
    while (cell.size() < n) {
      const std::uint16_t c = std::bernoulli_distribution(0.1)(rng) ? kNo : cell_of(rng);
      for (int k = run(rng); k > 0 && cell.size() < n; --k) cell.push_back(c);
    }
    std::vector<float> residual(n);
    for (float& r : residual) r = v(rng);
    in_cells += recorder_kernels::sumIntoCells(n, cell.data(), kNo, residual.data(), sum.data(),
                                               count.data(), touched.data(), slots, squares);
    for (std::size_t j = 0; j < n; ++j) {  // the scalar form it replaces
      if (cell[j] == kNo) continue;
      if (count_ref[cell[j]]++ == 0) touched_ref.push_back(cell[j]);
      sum_ref[cell[j]] += residual[j];
      squares_ref += static_cast<double>(residual[j]) * residual[j];
      ++in_cells_ref;
    }
  }
  EXPECT_EQ(squares, squares_ref);
  EXPECT_EQ(in_cells, in_cells_ref);
  for (std::uint16_t c = 0; c < kNo; ++c) {
    EXPECT_EQ(sum[c], sum_ref[c]) << c;
    EXPECT_EQ(count[c], count_ref[c]) << c;
  }
  EXPECT_EQ(sum[kNo], 0.0);  // only exact zeros added to the spare slot
  // Each touched cell once, in the order first seen; the spare slot may be among them.
  std::vector<std::uint32_t> seen(touched.begin(), touched.begin() + static_cast<long>(slots));
  seen.erase(std::remove(seen.begin(), seen.end(), kNo), seen.end());
  EXPECT_EQ(seen, touched_ref);
}

}  // namespace
}  // namespace freeinit::detail
