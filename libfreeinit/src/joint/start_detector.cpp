#include "joint/start_detector.h"

#include <freeinit/rotation.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

#include "joint/doppler_inertial_filter.h"
#include "joint/vector_clones.h"

namespace freeinit {
namespace {

/// The returns as linear equations in theta = (v_b0, g_b0, db_g), one array per quantity: the
/// refinement sweeps them seven times per hypothesis, four returns per vector operation.
/// With s = v_b0 + t g_b0 a return of direction w = R_0t u in b0 reads
///   e = -w^T s + c^T db_g + noise,   c = c0 + K s,
/// where c = p_bl x u - t v_b(t) x u is the gyro-bias column (refine() says why) and, from
/// v_b(t) = R_0t^T (s + C(t)) and x x u = -[u]x x,
///   c0 = p_bl x u - t (R_0t^T C(t)) x u,   K = t [u]x R_0t^T.
/// The column is linear in s: no rotation is applied per return and iteration.
struct Rows {
  /// The columns, one value per return: time [s], the equation's left-hand side [m/s], the
  /// direction w in b0, t w, the gyro-bias column at s = 0 (c0), and K, row-major (K0..K0 + 8).
  enum Column : int { T, E, WX, WY, WZ, TWX, TWY, TWZ, C0X, C0Y, C0Z, K0, kColumns = K0 + 9 };
  Eigen::Index size() const { return a.rows(); }
  void resize(Eigen::Index n) { a.resize(n, kColumns); }
  /// Every `step`-th row of `o`.
  static Rows every(const Rows& o, Eigen::Index step) {
    const Eigen::Index n = (o.size() + step - 1) / step;
    Rows r;
    r.resize(n);
    for (int c = 0; c < kColumns; ++c)
      r.a.col(c) = Eigen::Map<const Eigen::ArrayXd, 0, Eigen::InnerStride<>>(
          o.column(c), n, Eigen::InnerStride<>(step));
    return r;
  }
  const double* column(int c) const { return a.col(c).data(); }
  double* column(int c) { return a.col(c).data(); }
  double operator()(Eigen::Index i, int c) const { return a(i, c); }
  Vec3 w(Eigen::Index i) const { return Vec3(a(i, WX), a(i, WY), a(i, WZ)); }

  Eigen::Array<double, Eigen::Dynamic, kColumns> a;  ///< one column after the other
};

/// Field-of-view cells of the returns: a grid over the observed azimuth/elevation extent.
class CoverageGrid {
 public:
  explicit CoverageGrid(const std::vector<Vec3>& d_l) {
    std::vector<std::pair<double, double>> az_el;  // each direction's, computed once
    az_el.reserve(d_l.size());
    for (const Vec3& d : d_l) {
      const double az = std::atan2(d.y(), d.x());
      const double el = std::asin(std::clamp(d.z(), -1.0, 1.0));
      az_el.emplace_back(az, el);
      az_lo_ = std::min(az_lo_, az);
      az_hi_ = std::max(az_hi_, az);
      el_lo_ = std::min(el_lo_, el);
      el_hi_ = std::max(el_hi_, el);
    }
    cell_.reserve(d_l.size());
    totals_.fill(0);
    for (const auto& [az, el] : az_el) {
      const int c = cellOf(az, el);
      cell_.push_back(static_cast<std::uint8_t>(c));
      ++totals_[static_cast<std::size_t>(c)];
    }
  }
  /// Share of the occupied cells (at least 2 returns) in which most returns are inliers.
  /// `inlier(i)` tells whether return i is one.
  template <class Inlier>
  double coverage(const Inlier& inlier) const {
    std::array<int, kCells> in{};
    for (std::size_t i = 0; i < cell_.size(); ++i)
      if (inlier(i)) ++in[cell_[i]];
    int occupied = 0, supported = 0;
    for (std::size_t c = 0; c < kCells; ++c) {
      if (totals_[c] < 2) continue;
      ++occupied;
      if (2 * in[c] > totals_[c]) ++supported;
    }
    return occupied > 0 ? static_cast<double>(supported) / occupied : 0.0;
  }
  double coverage(const std::vector<std::uint8_t>& mask) const {
    return coverage([&](std::size_t i) { return mask[i] != 0; });
  }

 private:
  static constexpr int kAz = 16, kEl = 8;
  static constexpr std::size_t kCells = kAz * kEl;
  int cellOf(double az, double el) const {
    const auto bin = [](double x, double lo, double hi, int n) {
      if (!(hi > lo)) return 0;
      return std::clamp(static_cast<int>((x - lo) / (hi - lo) * n), 0, n - 1);
    };
    return bin(az, az_lo_, az_hi_, kAz) * kEl + bin(el, el_lo_, el_hi_, kEl);
  }
  double az_lo_ = 1e9, az_hi_ = -1e9, el_lo_ = 1e9, el_hi_ = -1e9;
  std::vector<std::uint8_t> cell_;
  std::array<int, kCells> totals_;
};

// The sweeps over the returns (the returns' equations, RANSAC's counts, the refinement's
// iterations) run four returns (or two rows of the normal equations' products) per vector
// operation, built for several instruction sets and chosen at load time (vector_clones.h). Each
// lane does one return's operations in the order the scalar formulas give them, so every build
// gives the same results.
#if defined(__GNUC__) && !defined(__clang__)
#define FREEINIT_START_INLINE __attribute__((always_inline)) inline
#else
#define FREEINIT_START_INLINE inline
#endif
// The helpers below return vectors by value. They are always inlined into the sweeps, so the
// calling convention such a vector would have across a call (which differs between the builds)
// never applies. (GCC reports it at the end of the file: the note is off from here on.)
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

/// The weighted equations q (a^T, e) of a return, 10 values per return, kept two returns to a
/// block of 20: value c of return r at [20 (r / 2) + 2 c + r % 2]. Two returns' values of one
/// column are side by side and two columns of a pair of returns are four consecutive values: the
/// products of a column with two others are one vector operation (gramBlocks()).
constexpr std::size_t kBlock = 20;

/// Buffers of the refinement, kept across its calls (no allocation per iteration).
struct RefineWork {
  explicit RefineWork(Eigen::Index n)
      : res(n),
        cx(n),
        cy(n),
        cz(n),
        blocks(static_cast<Eigen::Index>(kBlock) * 2 * ((n + 3) / 4)) {}
  /// The residuals e - a^T theta and the gyro-bias columns c, unweighted (finalResiduals()).
  Eigen::ArrayXd res, cx, cy, cz;
  /// The weighted equations (kBlock). Their products hold the normal equations (sum of w a a^T,
  /// w = q^2) and their right-hand side (sum of w e a) at once.
  Eigen::ArrayXd blocks;  // (not zeroed: what is read is written first)
};

// Four doubles: an AVX register, or two SSE2 ones in the baseline build.
typedef double V4 __attribute__((vector_size(32)));
typedef double V2 __attribute__((vector_size(16)));

FREEINIT_START_INLINE V4 load4(const double* p) {
  V4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

/// The returns' equations as the sweeps read them: Rows' columns, or a copy of their last few.
struct RowArrays {
  static constexpr int kArrays = Rows::kColumns;
  using Array = Rows::Column;
  std::array<const double*, kArrays> a;
  explicit RowArrays(const Rows& r) {
    for (int c = 0; c < kArrays; ++c) a[static_cast<std::size_t>(c)] = r.column(c);
  }
  /// Rows [i, i + count) (count < 4) of `o`, zero-padded to four, in `room`.
  RowArrays(const RowArrays& o, std::size_t i, std::size_t count,
            std::array<std::array<double, 4>, kArrays>& room) {
    for (std::size_t k = 0; k < a.size(); ++k) {
      room[k].fill(0.0);
      std::copy(o.a[k] + i, o.a[k] + i + count, room[k].begin());
      a[k] = room[k].data();
    }
  }
};

/// Returns i..i+3 of one of the arrays.
FREEINIT_START_INLINE V4 at(const RowArrays& r, int array, std::size_t i) {
  return load4(r.a[static_cast<std::size_t>(array)] + i);
}

/// The gyro-bias columns c of returns i..i+3 at s = v + t g, and their residuals e - a^T theta,
/// theta = (v_b0, g_b0, db_g).
struct FourRows {
  V4 cx, cy, cz, res;
};
FREEINIT_START_INLINE FourRows fourRows(const RowArrays& r, std::size_t i, const double* theta) {
  using A = RowArrays::Array;
  const V4 t = at(r, A::T, i);
  const V4 sx = theta[0] + t * theta[3], sy = theta[1] + t * theta[4], sz = theta[2] + t * theta[5];
  const int K = A::K0;
  FourRows o;
  o.cx = at(r, A::C0X, i) + at(r, K, i) * sx + at(r, K + 1, i) * sy + at(r, K + 2, i) * sz;
  o.cy = at(r, A::C0Y, i) + at(r, K + 3, i) * sx + at(r, K + 4, i) * sy + at(r, K + 5, i) * sz;
  o.cz = at(r, A::C0Z, i) + at(r, K + 6, i) * sx + at(r, K + 7, i) * sy + at(r, K + 8, i) * sz;
  o.res = (at(r, A::E, i) + (at(r, A::WX, i) * sx + at(r, A::WY, i) * sy + at(r, A::WZ, i) * sz)) -
          (o.cx * theta[6] + o.cy * theta[7] + o.cz * theta[8]);
  return o;
}

/// Residuals e - a^T theta of rows [0, n) and their gyro-bias columns c, unweighted.
FREEINIT_VECTOR_CLONES
void finalResiduals(const RowArrays& r, std::size_t n, const double* theta, double* __restrict res,
                    double* __restrict cx, double* __restrict cy, double* __restrict cz) {
  const auto store = [&](const FourRows& o, std::size_t i, std::size_t count) {
    for (std::size_t k = 0; k < count; ++k) {
      res[i + k] = o.res[k];
      cx[i + k] = o.cx[k];
      cy[i + k] = o.cy[k];
      cz[i + k] = o.cz[k];
    }
  };
  const std::size_t full = n - n % 4;
  for (std::size_t i = 0; i < full; i += 4) store(fourRows(r, i, theta), i, 4);
  if (full < n) {
    std::array<std::array<double, 4>, RowArrays::kArrays> room;
    const RowArrays last(r, full, n - full, room);
    store(fourRows(last, 0, theta), full, n - full);
  }
}

/// The weighted equations of returns i..i+3 (of `r`) as blocks (kBlock) at `out`: the Cauchy
/// weight's root q = q_num / (1 + (residual inv_scale)^2), a = (-w, -t w, c), q (a^T, e).
FREEINIT_START_INLINE void weighFour(const RowArrays& r, std::size_t i, const double* theta,
                                     double q_num, double inv_scale, double* out) {
  using A = RowArrays::Array;
  const FourRows o = fourRows(r, i, theta);
  const V4 u = o.res * inv_scale;
  const V4 q = q_num / (1.0 + u * u);
  const V4 nq = -q;
  const V4 m[10] = {nq * at(r, A::WX, i),
                    nq * at(r, A::WY, i),
                    nq * at(r, A::WZ, i),
                    nq * at(r, A::TWX, i),
                    nq * at(r, A::TWY, i),
                    nq * at(r, A::TWZ, i),
                    o.cx * q,
                    o.cy * q,
                    o.cz * q,
                    q * at(r, A::E, i)};
  // Returns i, i + 1 to one block, i + 2, i + 3 to the next.
  for (int c = 0; c < 10; ++c) {
    out[2 * c] = m[c][0];
    out[2 * c + 1] = m[c][1];
    out[kBlock + 2 * c] = m[c][2];
    out[kBlock + 2 * c + 1] = m[c][3];
  }
}

/// The weighted equations of rows [0, n) at theta as blocks (kBlock; room for a multiple of four
/// rows).
FREEINIT_VECTOR_CLONES
void weighRows(const RowArrays& r, std::size_t n, const double* theta, double q_num,
               double inv_scale, double* __restrict blocks) {
  const std::size_t full = n - n % 4;
  for (std::size_t i = 0; i < full; i += 4)
    weighFour(r, i, theta, q_num, inv_scale, blocks + kBlock * (i / 2));
  if (full < n) {
    std::array<std::array<double, 4>, RowArrays::kArrays> room;
    const RowArrays last(r, full, n - full, room);
    weighFour(last, 0, theta, q_num, inv_scale, blocks + kBlock * (full / 2));
  }
}

/// Column I of the lower triangle of the blocks' products over their first nb blocks: one sum per
/// pair of columns (2 p, 2 p + 1) from the pair that holds I on, its lanes (column 2 p's even and
/// odd rows, then column 2 p + 1's), kept in registers. N column-major 10x10.
template <int I>
FREEINIT_START_INLINE void gramColumn(const double* blocks, std::size_t nb, double* N) {
  constexpr int kFirst = I / 2, kPairs = 5 - kFirst;
  V4 sum[kPairs];
  for (V4& s : sum) s = V4{0, 0, 0, 0};
#pragma GCC unroll 2
  for (std::size_t b = 0; b < nb; ++b) {
    const double* x = blocks + kBlock * b;
    V2 a2;  // column I of the two rows, twice
    std::memcpy(&a2, x + 2 * I, sizeof a2);
    const V4 a = __builtin_shufflevector(a2, a2, 0, 1, 0, 1);
    for (int p = 0; p < kPairs; ++p) sum[p] += a * load4(x + 4 * (kFirst + p));
  }
  for (int p = 0; p < kPairs; ++p) {
    const int j = 2 * (kFirst + p);
    if (j >= I) N[10 * I + j] = sum[p][0] + sum[p][1];
    N[10 * I + j + 1] = sum[p][2] + sum[p][3];
  }
}

template <std::size_t... I>
FREEINIT_START_INLINE void gramColumns(const double* blocks, std::size_t nb, double* N,
                                       std::index_sequence<I...>) {
  (gramColumn<static_cast<int>(I)>(blocks, nb, N), ...);
}

/// Columns 0..8 of the lower triangle of the blocks' products (the (9, 9) entry is not needed).
FREEINIT_VECTOR_CLONES
void gramBlocks(const double* blocks, std::size_t nb, double* N) {
  gramColumns(blocks, nb, N, std::make_index_sequence<9>{});
}

/// RANSAC's candidate motions are scored on a pool of returns as arrays: e, w (x, y, z) and the
/// gravity term t w^T g, which RANSAC holds.
struct PoolArrays {
  const double *e, *wx, *wy, *wz, *tg;
  /// Return i's residual at the motion (vx, vy, vz): e + w^T v + t w^T g.
  double residual(std::size_t i, double vx, double vy, double vz) const {
    return (e[i] + (wx[i] * vx + wy[i] * vy + wz[i] * vz)) + tg[i];
  }
};

/// How many of the pool's first m returns the motion v explains (|e + w^T v + t w^T g| < gate),
/// four returns per vector operation; as soon as the returns left could not bring the count above
/// `best`, the count so far (which does not exceed it either).
FREEINIT_VECTOR_CLONES
std::size_t countWithin(const PoolArrays& pool, std::size_t m, const double* v, double gate,
                        std::size_t best) {
  const double vx = v[0], vy = v[1], vz = v[2];
  const V4 hi = {gate, gate, gate, gate}, lo = -hi;
  using Mask = decltype(hi < lo);  // -1 where true
  Mask in = {0, 0, 0, 0};
  const std::size_t full = m - m % 4;
  constexpr std::size_t kChunk = 64;  // returns between two looks at the count
  std::size_t i = 0;
  while (i < full) {
    for (const std::size_t end = std::min(full, i + kChunk); i < end; i += 4) {
      const V4 r = (load4(pool.e + i) +
                    (load4(pool.wx + i) * vx + load4(pool.wy + i) * vy + load4(pool.wz + i) * vz)) +
                   load4(pool.tg + i);
      in -= (r < hi) & (r > lo);
    }
    const std::size_t count = static_cast<std::size_t>((in[0] + in[1]) + (in[2] + in[3]));
    if (count + (m - i) <= best) return count;
  }
  std::size_t count = static_cast<std::size_t>((in[0] + in[1]) + (in[2] + in[3]));
  for (; i < m; ++i)
    if (std::abs(pool.residual(i, vx, vy, vz)) < gate) ++count;
  return count;
}

/// The products of the first n weighted equations (kBlock), lower triangle only (half the
/// products of a full one): rows 2 k and 2 k + 1 summed apart, then added, and an odd last row
/// added to that.
Eigen::Matrix<double, 10, 10> gram(const RefineWork& wk, std::size_t n) {
  Eigen::Matrix<double, 10, 10> N = Eigen::Matrix<double, 10, 10>::Zero();
  gramBlocks(wk.blocks.data(), n / 2, N.data());
  if (n % 2 != 0) {
    const double* x = wk.blocks.data() + kBlock * (n / 2);
    for (int i = 0; i < 10; ++i)
      for (int j = i; j < 10; ++j) N(j, i) += x[2 * i] * x[2 * j];
  }
  return N;
}

/// The strapdown motion over one IMU interval, from sample k at t_k to sample k + 1, from the
/// interpolants the integrator uses (integrate(): the cubics in the time s from t_k through the
/// samples around the interval), kept as monomial coefficients. Along the interval the
/// integrator's result for a time tau is, with W(s) the gyro minus its bias, F(s) the specific
/// force and the rotation vectors by Simpson's rule with the coning correction,
///   phi(tau) = tau/6 (W(0) + 4 W(tau/2) + W(tau)) + tau^2/12 W(0) x W(tau),
///   phi_h = tau/12 (W(0) + 4 W(tau/4) + W(tau/2)) + tau^2/48 W(0) x W(tau/2),
///   R(tau) = R_k Exp(phi(tau)) and, gravity cancelling between v(t) and g t,
///   C(t_k + tau) = C(t_k) + tau/6 R_k (F(0) + 4 Exp(phi_h) F(tau/2) + Exp(phi(tau)) F(tau)).
/// The integrator evaluates the interpolants at the absolute times t_k + s, rounded to the
/// precision of the time stamps (0.2 us for a time stamp of 1.7e9 s), so W and F are taken at
/// those rounded offsets here too: the results are the integrator's up to the rounding of the
/// arithmetic.
struct IntervalMotion {
  double t_k = 0;                          ///< [s] the sample's time stamp
  std::array<double, 9> R;                 ///< R_0k, row-major
  std::array<double, 3> C;                 ///< [m/s] C(t_k)
  std::array<std::array<double, 3>, 4> W;  ///< [rad/s^(m+1)] the gyro minus its bias, s^m
  std::array<std::array<double, 3>, 4> F;  ///< [m/s^(m+2)] the specific force, s^m
};

/// The interval from sample k of `imu`, with the integrator's state x there (its biases are
/// removed) and t_k [s] its time from the window start.
IntervalMotion intervalMotion(const std::vector<ImuSample>& imu, std::size_t k,
                              const FilterState& x, double t_k) {
  // The interpolants' monomial coefficients: sum over the samples a of the Lagrange basis
  // polynomial L_a(s) = prod_(b != a) (s - s_b) / (s_a - s_b) times the sample, s from imu[k].t.
  std::size_t lo = 0;
  const std::size_t hi =
      DopplerInertialFilter::interpolationSpan(imu, imu[k].t, k, lo);  // what integrate() uses
  std::array<Vec3, 4> w, f;
  for (std::size_t m = 0; m < 4; ++m) w[m] = f[m] = Vec3::Zero();
  for (std::size_t a = lo; a <= hi; ++a) {
    std::array<double, 4> L = {1, 0, 0, 0};
    for (std::size_t b = lo; b <= hi; ++b) {
      if (b == a) continue;
      const double s_b = imu[b].t - imu[k].t, inv = 1.0 / (imu[a].t - imu[b].t);
      for (std::size_t m = 3; m > 0; --m) L[m] = (L[m - 1] - s_b * L[m]) * inv;
      L[0] = -s_b * L[0] * inv;
    }
    for (std::size_t m = 1; m < 4; ++m) {
      w[m] += L[m] * imu[a].gyro;
      f[m] += L[m] * imu[a].accel;
    }
  }
  // At s = 0 the sample itself, as the integrator takes it.
  w[0] = imu[k].gyro - x.b_g;
  f[0] = imu[k].accel - x.b_a;
  IntervalMotion im;
  im.t_k = imu[k].t;
  const Vec3 C = x.v_w - Vec3(0, 0, -kGravity) * t_k;
  for (int r = 0; r < 3; ++r) {
    im.C[static_cast<std::size_t>(r)] = C(r);
    for (int c = 0; c < 3; ++c) im.R[static_cast<std::size_t>(3 * r + c)] = x.R_wb(r, c);
    for (std::size_t m = 0; m < 4; ++m) {
      im.W[m][static_cast<std::size_t>(r)] = w[m](r);
      im.F[m][static_cast<std::size_t>(r)] = f[m](r);
    }
  }
  return im;
}

/// Returns of the span as they are given (times from the window start, tau from their interval's
/// sample, direction in the LiDAR frame, Doppler), one array per quantity.
struct ReturnArrays {
  const double *t, *tau, *dx, *dy, *dz, *z;
};

/// The equations' arrays (Rows) from a given row on.
struct RowOutputs {
  std::array<double*, RowArrays::kArrays> a;  // in RowArrays::Array's order
  RowOutputs(Rows& r, Eigen::Index from) {
    for (int c = 0; c < RowArrays::kArrays; ++c)
      a[static_cast<std::size_t>(c)] = r.column(c) + from;
  }
};

/// Exp(phi) = I + a [phi]x + b [phi]x^2 of four rotation vectors: a = sin(theta) / theta and
/// b = (1 - cos(theta)) / theta^2 (theta^2 = x) by their Taylor series up to x^6, within half a
/// unit of the last place for theta <= 0.5 (far more than any platform turns within one IMU
/// interval); beyond, from the sine and the cosine.
FREEINIT_START_INLINE void expCoefficients(const V4& x, V4& a, V4& b) {
  a = 1.0 +
      x * (-1.0 / 6 +
           x * (1.0 / 120 + x * (-1.0 / 5040 + x * (1.0 / 362880 + x * (-1.0 / 39916800 +
                                                                        x * (1.0 / 6227020800))))));
  b = 0.5 + x * (-1.0 / 24 +
                 x * (1.0 / 720 +
                      x * (-1.0 / 40320 + x * (1.0 / 3628800 +
                                               x * (-1.0 / 479001600 + x * (1.0 / 87178291200))))));
  for (int l = 0; l < 4; ++l) {
    if (!(x[l] > 0.25)) continue;
    const double theta = std::sqrt(x[l]);
    a[l] = std::sin(theta) / theta;
    b[l] = (1.0 - std::cos(theta)) / x[l];
  }
}

/// sum_m c[m] s^m (kTerms >= 2) of each of three components, by Horner's rule.
template <std::size_t kTerms>
FREEINIT_START_INLINE void polynomial(const std::array<std::array<double, 3>, kTerms>& c,
                                      const V4& s, V4 (&out)[3]) {
  for (std::size_t r = 0; r < 3; ++r) {
    V4 y = s * c[kTerms - 1][r] + c[kTerms - 2][r];
    for (std::size_t m = kTerms - 2; m-- > 0;) y = y * s + c[m][r];
    out[r] = y;
  }
}

/// p[0..3], or its first `count` values and zeros (finite values in the unused lanes).
template <bool kFull>
FREEINIT_START_INLINE V4 loadSome(const double* p, std::size_t count) {
  if (kFull) return load4(p);
  double padded[4] = {};
  std::copy(p, p + count, padded);
  return load4(padded);
}

/// The equations of four returns (the first `count` of them valid) of one interval: the rotation
/// and C at each return from the interval's polynomials, then Rows' quantities (see there).
template <bool kFull>
FREEINIT_START_INLINE void fourEquations(const IntervalMotion& im, const Extrinsics& ex,
                                         const ReturnArrays& in, std::size_t i, std::size_t count,
                                         const RowOutputs& out) {
  const V4 t = loadSome<kFull>(in.t + i, count), tau = loadSome<kFull>(in.tau + i, count),
           dx = loadSome<kFull>(in.dx + i, count), dy = loadSome<kFull>(in.dy + i, count),
           dz = loadSome<kFull>(in.dz + i, count), z = loadSome<kFull>(in.z + i, count);
  const auto& R = im.R;
  // The interpolants at the offsets the integrator takes them at (IntervalMotion).
  const V4 s1 = (im.t_k + 0.25 * tau) - im.t_k, s2 = (im.t_k + 0.5 * tau) - im.t_k,
           s3 = (im.t_k + tau) - im.t_k;
  V4 W1[3], W2[3], W3[3], F[3], F_h[3];
  polynomial(im.W, s1, W1);
  polynomial(im.W, s2, W2);
  polynomial(im.W, s3, W3);
  polynomial(im.F, s2, F_h);
  polynomial(im.F, s3, F);
  const auto& W0 = im.W[0];
  // Rotation vectors over [0, tau/2] and [0, tau]: Exp(phi) as a matrix E, Exp(phi_h) applied to
  // F(tau/2) only (Rodrigues).
  const V4 ch = 0.5 * tau / 6.0, cc_h = 0.25 * tau * tau / 12.0, c1 = tau / 6.0,
           cc = tau * tau / 12.0;
  const V4 phi_h[3] = {
      ch * ((W0[0] + 4.0 * W1[0]) + W2[0]) + (W0[1] * W2[2] - W0[2] * W2[1]) * cc_h,
      ch * ((W0[1] + 4.0 * W1[1]) + W2[1]) + (W0[2] * W2[0] - W0[0] * W2[2]) * cc_h,
      ch * ((W0[2] + 4.0 * W1[2]) + W2[2]) + (W0[0] * W2[1] - W0[1] * W2[0]) * cc_h};
  const V4 phi[3] = {c1 * ((W0[0] + 4.0 * W2[0]) + W3[0]) + (W0[1] * W3[2] - W0[2] * W3[1]) * cc,
                     c1 * ((W0[1] + 4.0 * W2[1]) + W3[1]) + (W0[2] * W3[0] - W0[0] * W3[2]) * cc,
                     c1 * ((W0[2] + 4.0 * W2[2]) + W3[2]) + (W0[0] * W3[1] - W0[1] * W3[0]) * cc};
  const V4 sq = phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2];
  V4 a, b, a_h, b_h;
  expCoefficients(sq, a, b);
  expCoefficients(phi_h[0] * phi_h[0] + phi_h[1] * phi_h[1] + phi_h[2] * phi_h[2], a_h, b_h);
  V4 E[3][3];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) E[r][c] = b * (phi[r] * phi[c]);
    E[r][r] += 1.0 - b * sq;
  }
  E[0][1] -= a * phi[2];
  E[1][0] += a * phi[2];
  E[0][2] += a * phi[1];
  E[2][0] -= a * phi[1];
  E[1][2] -= a * phi[0];
  E[2][1] += a * phi[0];
  // Exp(phi_h) F_h = F_h + a_h phi_h x F_h + b_h phi_h x (phi_h x F_h).
  const V4 p1[3] = {phi_h[1] * F_h[2] - phi_h[2] * F_h[1], phi_h[2] * F_h[0] - phi_h[0] * F_h[2],
                    phi_h[0] * F_h[1] - phi_h[1] * F_h[0]};
  const V4 p2[3] = {phi_h[1] * p1[2] - phi_h[2] * p1[1], phi_h[2] * p1[0] - phi_h[0] * p1[2],
                    phi_h[0] * p1[1] - phi_h[1] * p1[0]};
  V4 S[3];  // F(0) + 4 Exp(phi_h) F_h + E F
  for (int r = 0; r < 3; ++r)
    S[r] = im.F[0][static_cast<std::size_t>(r)] + 4.0 * (F_h[r] + a_h * p1[r] + b_h * p2[r]) +
           (E[r][0] * F[0] + E[r][1] * F[1] + E[r][2] * F[2]);
  V4 Rt[3][3], C[3];  // R(tau) = R_k E, C(tau)
  for (int r = 0; r < 3; ++r) {
    const double r0 = R[3 * r], r1 = R[3 * r + 1], r2 = R[3 * r + 2];
    for (int c = 0; c < 3; ++c) Rt[r][c] = r0 * E[0][c] + r1 * E[1][c] + r2 * E[2][c];
    C[r] = im.C[static_cast<std::size_t>(r)] + c1 * (r0 * S[0] + r1 * S[1] + r2 * S[2]);
  }
  // The return's equation.
  const Mat3& Rbl = ex.R_bl;
  const V4 u[3] = {Rbl(0, 0) * dx + Rbl(0, 1) * dy + Rbl(0, 2) * dz,
                   Rbl(1, 0) * dx + Rbl(1, 1) * dy + Rbl(1, 2) * dz,
                   Rbl(2, 0) * dx + Rbl(2, 1) * dy + Rbl(2, 2) * dz};
  const Vec3& p = ex.p_bl;
  const V4 pu[3] = {p.y() * u[2] - p.z() * u[1], p.z() * u[0] - p.x() * u[2],
                    p.x() * u[1] - p.y() * u[0]};  // p_bl x u
  V4 w[3], RtC[3];                                 // R u, R^T C
  for (int r = 0; r < 3; ++r) {
    w[r] = Rt[r][0] * u[0] + Rt[r][1] * u[1] + Rt[r][2] * u[2];
    RtC[r] = Rt[0][r] * C[0] + Rt[1][r] * C[1] + Rt[2][r] * C[2];
  }
  V4 o[RowArrays::kArrays];
  using A = RowArrays::Array;
  o[A::T] = t;
  // u^T (omega x p_bl) = omega^T (p_bl x u)
  o[A::E] = z + (W3[0] * pu[0] + W3[1] * pu[1] + W3[2] * pu[2]) +
            (w[0] * C[0] + w[1] * C[1] + w[2] * C[2]);
  for (int r = 0; r < 3; ++r) {
    o[A::WX + r] = w[r];
    o[A::TWX + r] = t * w[r];
  }
  // c0 = p_bl x u - t (R^T C) x u
  o[A::C0X] = pu[0] - t * (RtC[1] * u[2] - RtC[2] * u[1]);
  o[A::C0Y] = pu[1] - t * (RtC[2] * u[0] - RtC[0] * u[2]);
  o[A::C0Z] = pu[2] - t * (RtC[0] * u[1] - RtC[1] * u[0]);
  // K = t [u]x R^T: its column c is t u x (row c of R); row-major in the arrays.
  for (int c = 0; c < 3; ++c) {
    o[A::K0 + c] = t * (u[1] * Rt[c][2] - u[2] * Rt[c][1]);
    o[A::K0 + 3 + c] = t * (u[2] * Rt[c][0] - u[0] * Rt[c][2]);
    o[A::K0 + 6 + c] = t * (u[0] * Rt[c][1] - u[1] * Rt[c][0]);
  }
#pragma GCC unroll 20
  for (std::size_t k = 0; k < RowArrays::kArrays; ++k) {
    if (kFull) {
      std::memcpy(out.a[k] + i, &o[k], sizeof(V4));
    } else {
      for (std::size_t l = 0; l < count; ++l) out.a[k][i + l] = o[k][l];
    }
  }
}

/// The equations of the n returns `in` of one interval into `out`.
FREEINIT_VECTOR_CLONES
void intervalEquations(const IntervalMotion& im, const Extrinsics& ex, const ReturnArrays& in,
                       std::size_t n, const RowOutputs& out) {
  const std::size_t full = n - n % 4;
  for (std::size_t i = 0; i < full; i += 4) fourEquations<true>(im, ex, in, i, 4, out);
  if (full < n) fourEquations<false>(im, ex, in, full, n - full, out);
}

/// The refinements' states after their first, thinned iterations. Two refinements that get there
/// so close that no return's residual differs by a tenth of the Doppler noise end at the same
/// hypothesis: the remaining iterations contract their difference (the refinements of one motion
/// from different RANSAC starts are within 1e-3 m/s of each other at that point and end within
/// 1e-6 m/s with the same inliers; distinct motions are tenths of m/s apart). The later one would
/// only be merged into the earlier one's result, so it is stopped there.
struct EarlyStates {
  double span = 0;   ///< [s] T
  double lever = 0;  ///< [m] |p_bl|
  std::vector<Eigen::Matrix<double, 9, 1>> seen;
  bool same(const Eigen::Matrix<double, 9, 1>& a, const Eigen::Matrix<double, 9, 1>& b,
            double doppler_sigma) const {
    // Largest change of a residual: w^T dv + t w^T dg + c^T ddb, |c| <= |p_bl| + t |v_b|.
    const double dz = (a.head<3>() - b.head<3>()).norm() +
                      span * (a.segment<3>(3) - b.segment<3>(3)).norm() +
                      (lever + span * a.head<3>().norm()) * (a.tail<3>() - b.tail<3>()).norm();
    return dz < 0.1 * doppler_sigma;
  }
};

/// StartHypothesis::residual_scale of the residuals `res`, from `gate` [m/s] on.
void robustScale(const Eigen::Ref<const Eigen::ArrayXd>& res, double gate, StartHypothesis& h) {
  std::vector<double> a;
  a.reserve(static_cast<std::size_t>(res.size()));
  double scale = 0, limit = gate;
  for (int iteration = 0; iteration < 3; ++iteration) {
    a.clear();
    for (Eigen::Index i = 0; i < res.size(); ++i)
      if (std::abs(res(i)) <= limit) a.push_back(std::abs(res(i)));
    if (a.size() < 10) return;
    auto mid = a.begin() + static_cast<std::ptrdiff_t>(a.size() / 2);
    std::nth_element(a.begin(), mid, a.end());
    const double m = *mid;
    constexpr double kMadToSigma = 1.4826;
    scale = kMadToSigma * m;
    const double next = std::max(gate, 5.0 * scale);
    if (next == limit) break;
    limit = next;
  }
  h.residual_scale = scale;
  h.residual_scale_returns = a.size();
}

/// IRLS (Cauchy) refinement of theta = (v_b0, g_b0, db_g) from a start, with a weak gravity
/// prior and the gyro-bias prior. A gyro-bias error db turns the body-frame velocity by
/// -t db x v_b(t) over the span and the lever-arm velocity by -db x p_bl, so that the Doppler of a
/// return changes by (p_bl x u - t v_b(t) x u)^T db (first order; the effect of db on the
/// integrated specific force, t^2 |f| db, is neglected). At speed this is what limits the gravity
/// of so short a span: it must be in its covariance.
/// `at_rest`: the rest hypothesis, velocity zero and gravity the mean specific force (the moving
/// objects of a static start must not bend either: only the gyro-bias correction is fitted).
/// `sub`: every third row of `rows` (for the first iterations); `inliers` (if given) receives
/// which rows the refined motion explains; `g_sigma_max` [m/s^2] caps the gravity prior's std.
/// `early` (if given): nothing is returned when the refinement reaches one of its states.
std::optional<StartHypothesis> refine(const Rows& rows, const Rows& sub, const CoverageGrid& grid,
                                      RefineWork& wk, const Vec3& v_start, const Vec3& g_prior,
                                      bool at_rest, const StartDetectorParams& p,
                                      std::vector<std::uint8_t>* inliers = nullptr,
                                      double g_sigma_max = 4.0, EarlyStates* early = nullptr) {
  using Vec9 = Eigen::Matrix<double, 9, 1>;
  using Mat9 = Eigen::Matrix<double, 9, 9>;
  Vec9 theta;  // (v, g, db)
  theta << v_start, g_prior, Vec3::Zero();
  const RowArrays all(rows), thinned(sub);
  const double inv_r = 1.0 / (p.doppler_sigma * p.doppler_sigma);
  // Gravity prior: the mean specific force is within a few m/s^2 of it on any real platform in
  // motion; at rest it is gravity minus the accelerometer bias, held.
  const double g_prior_var = at_rest ? 1e-12 : g_sigma_max * g_sigma_max;
  const double bg_prior_var = p.gyro_bias_sigma * p.gyro_bias_sigma;
  // (Cauchy scale [m/s], gravity prior std [m/s^2]) per iteration. Gravity is held near its prior
  // at first: free from the start, it would let the returns of a large moving object that are
  // consistent with the start only along some directions pull the motion towards theirs.
  static constexpr std::array<std::pair<double, double>, 7> schedule = {
      {{0.3, 0.5}, {0.3, 1.0}, {0.2, 4.0}, {0.15, 4.0}, {0.1, 4.0}, {0.1, 4.0}, {0.1, 4.0}}};
  constexpr std::size_t kEarly = 3;  // the last of the thinned iterations (EarlyStates)
  for (std::size_t iteration = 0; iteration < schedule.size(); ++iteration) {
    const auto [c, g_sigma] = schedule[iteration];
    // The first iterations, which only find the inliers, take every third return (weighted
    // three times), the last ones every return.
    const bool thin = iteration + 3 < schedule.size() && rows.size() > 1500;
    const Rows& r = thin ? sub : rows;
    const double step = thin ? 3.0 : 1.0;
    const double g_var = at_rest ? g_prior_var : std::min(g_sigma * g_sigma, g_prior_var);
    // Cauchy weight w = step / (sigma^2 (1 + u^2)^2), u = residual / scale: its square root.
    const double inv_scale = 1.0 / std::max(c, 3.0 * p.doppler_sigma);
    const std::size_t n_r = static_cast<std::size_t>(r.size());
    weighRows(thin ? thinned : all, n_r, theta.data(), std::sqrt(step * inv_r), inv_scale,
              wk.blocks.data());
    const Eigen::Matrix<double, 10, 10> N = gram(wk, n_r);
    // Lower triangle only (what the solvers below read): the right-hand side is the last row.
    Mat9 A = N.topLeftCorner<9, 9>();
    Vec9 b = N.row(9).head<9>().transpose();
    A.block<3, 3>(3, 3).diagonal().array() += 1.0 / g_var;
    b.segment<3>(3) += g_prior / g_var;
    A.block<3, 3>(6, 6).diagonal().array() += 1.0 / bg_prior_var;
    if (at_rest) {
      A.topLeftCorner<3, 3>().diagonal().array() += 1e12;
      b.head<3>() += v_start * 1e12;
    }
    const Vec9 next = A.ldlt().solve(b);
    if (!next.allFinite()) break;
    theta = next;
    if (early != nullptr && iteration == kEarly) {
      for (const Vec9& o : early->seen)
        if (early->same(theta, o, p.doppler_sigma)) return std::nullopt;
      early->seen.push_back(theta);
    }
  }
  StartHypothesis h;
  const Vec3 v = theta.head<3>();
  h.v_b0 = v;
  h.g_b0 = theta.segment<3>(3);
  // The inliers' information (weight 1/sigma^2 each), their equations gathered first: the motion
  // of a small object explains a few returns of thousands.
  const Eigen::Index n = rows.size();
  finalResiduals(all, static_cast<std::size_t>(n), theta.data(), wk.res.data(), wk.cx.data(),
                 wk.cy.data(), wk.cz.data());
  const auto res = wk.res.head(n);
  const Eigen::Array<bool, Eigen::Dynamic, 1> inl = !(res.abs() > p.gate);  // within the gate
  const double ss = inl.select(res.square(), 0.0).sum();
  const double s = std::sqrt(inv_r);
  std::size_t m = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!inl(i)) continue;
    const std::array<double, 10> x = {-s * rows(i, Rows::WX),
                                      -s * rows(i, Rows::WY),
                                      -s * rows(i, Rows::WZ),
                                      -s * rows(i, Rows::TWX),
                                      -s * rows(i, Rows::TWY),
                                      -s * rows(i, Rows::TWZ),
                                      s * wk.cx[i],
                                      s * wk.cy[i],
                                      s * wk.cz[i],
                                      s * rows(i, Rows::E)};
    double* block = wk.blocks.data() + kBlock * (m / 2) + m % 2;
    for (std::size_t c = 0; c < 10; ++c) block[2 * c] = x[c];
    ++m;
  }
  h.inliers = m;
  Mat9 info = gram(wk, m).topLeftCorner<9, 9>();
  info.block<3, 3>(3, 3).diagonal().array() += 1.0 / g_prior_var;
  info.block<3, 3>(6, 6).diagonal().array() += 1.0 / bg_prior_var;
  h.residual_rms = h.inliers > 0 ? std::sqrt(ss / static_cast<double>(h.inliers)) : 0.0;
  robustScale(res, p.gate, h);
  const double k = std::max(1.0, h.residual_rms / p.doppler_sigma);
  const Mat9 cov = info.ldlt().solve(Mat9::Identity()) * k * k;
  h.cov = cov.topLeftCorner<6, 6>();
  std::vector<std::uint8_t> mask(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) mask[static_cast<std::size_t>(i)] = inl(i) ? 1 : 0;
  h.coverage = grid.coverage(mask);
  if (inliers != nullptr) *inliers = std::move(mask);
  h.rest = v.norm() < p.max_speed;
  h.min_info_eigen =
      Eigen::SelfAdjointEigenSolver<Mat3>(info.topLeftCorner<3, 3>()).eigenvalues()(0);
  return h;
}

/// The clock offset's column of the returns' equations. With the LiDAR clock ahead of the IMU's by
/// delta, a return stamped t was taken at t - delta and measures z(t) - delta dz/dt, z the model's
/// Doppler (Rows). In b0, with Omega = R_0t omega, F = R_0t f, A = R_0t alpha (alpha the gyro's
/// rate), P = R_0t p_bl and m = Omega x w,
///   -dz/dt = u^T (-omega x v_b + f + R_0t^T g_b0 + alpha x p_bl)
///          = m^T (v_b0 + t g_b0) + w^T g_b0 + m^T C + w^T (F + A x P),
/// linear in (v_b0, g_b0) (the gyro bias' share neglected): the equation e = a^T theta gains
/// delta (m^T v_b0 + (t m + w)^T g_b0 + k0), k0 = m^T C + w^T (F + A x P). Omega, C and
/// F + A x P are interpolated linearly between the IMU samples: the column multiplies a few
/// milliseconds, its error of a few per cent is far below the Doppler noise.
struct OffsetColumns {
  Eigen::ArrayXd mx, my, mz, k0;
};

/// What refineOffset() fits.
struct OffsetFit {
  Eigen::Matrix<double, 9, 1> theta;  ///< (v_b0, g_b0, db_g)
  double delta = 0;                   ///< [s]
};

/// IRLS (Cauchy, as refine()'s last iterations) of theta = (v_b0, g_b0, db_g) and the clock offset
/// delta (prior: zero, p.time_offset_sigma) by Gauss-Newton on the bilinear equations
/// (OffsetColumns), from `start` (a refined hypothesis), gravity about g_prior with std g_sigma.
/// The hypothesis' quantities as refine() gives them, with the offset's std in time_offset_sigma
/// and marginalized out of cov.
StartHypothesis refineOffset(const Rows& rows, const OffsetColumns& oc, const CoverageGrid& grid,
                             RefineWork& wk, const StartHypothesis& start, const Vec3& g_prior,
                             double g_sigma, int iterations, const StartDetectorParams& p,
                             std::vector<std::uint8_t>& mask) {
  using Vec10 = Eigen::Matrix<double, 10, 1>;
  using Mat10 = Eigen::Matrix<double, 10, 10>;
  Vec10 x;
  x << start.v_b0, start.g_b0, Vec3::Zero(), start.time_offset;
  const RowArrays all(rows);
  const std::size_t n = static_cast<std::size_t>(rows.size());
  const double inv_r = 1.0 / (p.doppler_sigma * p.doppler_sigma);
  const double g_var = g_sigma * g_sigma, bg_var = p.gyro_bias_sigma * p.gyro_bias_sigma;
  const double dt_var = p.time_offset_sigma * p.time_offset_sigma;
  const double inv_scale = 1.0 / std::max(0.1, 3.0 * p.doppler_sigma);
  const double *T = rows.column(Rows::T), *WX = rows.column(Rows::WX), *WY = rows.column(Rows::WY),
               *WZ = rows.column(Rows::WZ);
  // The equation of row i at x: its residual, and its Jacobian J (de/dx) in j.
  auto equation = [&](std::size_t i, double* j) {
    const double w[3] = {WX[i], WY[i], WZ[i]}, m[3] = {oc.mx[i], oc.my[i], oc.mz[i]};
    const double t = T[i], delta = x(9);
    double col = oc.k0[i];
    for (int a = 0; a < 3; ++a) col += m[a] * x(a) + (t * m[a] + w[a]) * x(3 + a);
    for (int a = 0; a < 3; ++a) {
      j[a] = -w[a] + delta * m[a];
      j[3 + a] = -t * w[a] + delta * (t * m[a] + w[a]);
    }
    j[6] = wk.cx[i];
    j[7] = wk.cy[i];
    j[8] = wk.cz[i];
    j[9] = col;
    return wk.res[i] - delta * col;
  };
  // Sums of weight j j^T (lower triangle) and weight r j, as plain arrays (a loop the compiler
  // unrolls: this runs over every row of the span).
  struct Normal {
    double A[10][10] = {};
    double b[10] = {};
    void add(const double* j, double wgt, double r) {
      for (int a = 0; a < 10; ++a) {
        const double wj = wgt * j[a];
        for (int c = 0; c <= a; ++c) A[a][c] += wj * j[c];
        b[a] += wj * r;
      }
    }
    Mat10 matrix() const {
      Mat10 M;
      for (int a = 0; a < 10; ++a)
        for (int c = 0; c <= a; ++c) M(a, c) = M(c, a) = A[a][c];
      return M;
    }
  };
  double j[10];
  for (int it = 0; it < iterations; ++it) {
    finalResiduals(all, n, x.data(), wk.res.data(), wk.cx.data(), wk.cy.data(), wk.cz.data());
    Normal ne;
    for (std::size_t i = 0; i < n; ++i) {
      const double r = equation(i, j);
      const double u = r * inv_scale;
      ne.add(j, inv_r / ((1.0 + u * u) * (1.0 + u * u)), r);
    }
    Mat10 A = ne.matrix();
    Vec10 b = Eigen::Map<const Vec10>(ne.b);
    A.block<3, 3>(3, 3).diagonal().array() += 1.0 / g_var;
    b.segment<3>(3) += (g_prior - x.segment<3>(3)) / g_var;
    A.block<3, 3>(6, 6).diagonal().array() += 1.0 / bg_var;
    b.segment<3>(6) -= x.segment<3>(6) / bg_var;
    A(9, 9) += 1.0 / dt_var;
    b(9) -= x(9) / dt_var;
    const Vec10 step = A.ldlt().solve(b);
    if (!step.allFinite()) break;
    x += step;
  }
  // The inliers' information (weight 1/sigma^2 each), as refine() has it.
  finalResiduals(all, n, x.data(), wk.res.data(), wk.cx.data(), wk.cy.data(), wk.cz.data());
  Normal ni;
  double ss = 0;
  mask.assign(n, 0);
  std::size_t inliers = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double r = equation(i, j);
    wk.res[static_cast<Eigen::Index>(i)] = r;  // with the offset's share, for robustScale()
    if (std::abs(r) > p.gate) continue;
    mask[i] = 1;
    ++inliers;
    ss += r * r;
    ni.add(j, inv_r, 0.0);
  }
  Mat10 info = ni.matrix();
  info.block<3, 3>(3, 3).diagonal().array() += 1.0 / g_var;
  info.block<3, 3>(6, 6).diagonal().array() += 1.0 / bg_var;
  info(9, 9) += 1.0 / dt_var;
  StartHypothesis h = start;
  h.v_b0 = x.head<3>();
  h.g_b0 = x.segment<3>(3);
  h.time_offset = x(9);
  h.inliers = inliers;
  h.residual_rms = inliers > 0 ? std::sqrt(ss / static_cast<double>(inliers)) : 0.0;
  // The noise the residuals show is that of this fit: the start's carried the offset's error.
  robustScale(wk.res.head(static_cast<Eigen::Index>(n)), p.gate, h);
  const double k = std::max(1.0, h.residual_rms / p.doppler_sigma);
  const Mat10 cov = info.ldlt().solve(Mat10::Identity()) * k * k;
  h.cov = cov.topLeftCorner<6, 6>();
  h.time_offset_sigma = std::sqrt(std::max(cov(9, 9), 0.0));
  h.coverage = grid.coverage(mask);
  h.rest = h.v_b0.norm() < p.max_speed;
  h.min_info_eigen =
      Eigen::SelfAdjointEigenSolver<Mat3>(info.topLeftCorner<3, 3>()).eigenvalues()(0);
  h.plausible_gravity = std::abs(h.g_b0.norm() - kGravity) <= p.max_gravity_error;
  return h;
}

/// OffsetColumns of the rows of decideStart(): `at` the integrator's state at each sample of the
/// span from `span[j0]` on (times from t_ref), `interval` and `tau` each row's sample and time
/// after it.
OffsetColumns offsetColumns(const Rows& rows, const std::vector<ImuSample>& span, std::size_t j0,
                            const std::vector<FilterState>& at,
                            const std::vector<std::size_t>& interval,
                            const std::vector<double>& tau, const Extrinsics& ex, double t_ref) {
  // Omega, C and G = F + A x P at each sample.
  const std::size_t ns = at.size();
  std::vector<Vec3> Om(ns), C(ns), G(ns);
  std::vector<double> t(ns);
  const Vec3 g_w(0, 0, -kGravity);
  for (std::size_t k = 0; k < ns; ++k) {
    Vec3 gyro, accel, rate;
    t[k] = span[j0 + k].t;
    DopplerInertialFilter::interpolateImu(span, t[k], gyro, accel, j0 + k, &rate);
    const Mat3& R = at[k].R_wb;
    Om[k] = R * (gyro - at[k].b_g);
    C[k] = at[k].v_w - g_w * (t[k] - t_ref);
    G[k] = R * (accel - at[k].b_a) + (R * rate).cross(R * ex.p_bl);
  }
  OffsetColumns oc;
  const Eigen::Index n = rows.size();
  for (Eigen::ArrayXd* a : {&oc.mx, &oc.my, &oc.mz, &oc.k0}) a->resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::size_t k = interval[static_cast<std::size_t>(i)];
    const double f = k + 1 < ns ? tau[static_cast<std::size_t>(i)] / (t[k + 1] - t[k]) : 0.0;
    const std::size_t k1 = k + 1 < ns ? k + 1 : k;
    const Vec3 w = rows.w(i);
    const Vec3 m = ((1 - f) * Om[k] + f * Om[k1]).cross(w);
    oc.mx[i] = m.x();
    oc.my[i] = m.y();
    oc.mz[i] = m.z();
    oc.k0[i] = m.dot((1 - f) * C[k] + f * C[k1]) + w.dot((1 - f) * G[k] + f * G[k1]);
  }
  return oc;
}

/// The chosen motion's returns must constrain the velocity in every direction.
StartDecision& checkConditioning(StartDecision& d, const StartDetectorParams& p) {
  if (d.chosen.min_info_eigen >= p.min_info_eigen) return d;
  d.kind = StartDecision::Kind::Degenerate;
  d.message = "the point directions do not constrain the velocity (weakest information " +
              std::to_string(d.chosen.min_info_eigen) + " < " + std::to_string(p.min_info_eigen) +
              " 1/(m/s)^2)";
  return d;
}

}  // namespace

StartSpan startSpan(const std::vector<ImuSample>& imu, double t_first, const FreeInitConfig& cfg) {
  StartSpan out;
  std::size_t k = 0;
  while (k < imu.size() && imu[k].t < t_first) ++k;
  if (k + 1 >= imu.size()) return out;
  const double t_ref = imu[k].t;
  const double span = std::min(cfg.start.duration, cfg.window.duration);
  std::size_t k_last = k;
  while (k_last + 1 < imu.size() && imu[k_last].t < t_ref + span &&
         imu[k_last + 1].t - t_ref < cfg.window.duration)
    ++k_last;
  out.k_first = k;
  out.k_last = k_last;
  out.valid = true;
  out.complete = imu[k_last].t >= t_ref + span ||
                 (k_last + 1 < imu.size() && imu[k_last + 1].t - t_ref >= cfg.window.duration);
  return out;
}

StartDetectorParams startDetectorParams(const FreeInitConfig& cfg) {
  StartDetectorParams sp;
  sp.doppler_sigma = cfg.doppler.doppler_sigma;
  sp.gyro_sigma = cfg.imu.gyro_sigma;
  sp.accel_sigma = cfg.imu.accel_sigma;
  sp.gyro_bias_sigma = cfg.imu.gyro_bias_sigma0;
  sp.accel_bias_bound = cfg.imu.accel_bias_bound;
  sp.gate = cfg.doppler.gate_min;
  sp.max_speed = cfg.start.rest_speed;
  sp.min_info_eigen = cfg.start.min_info_eigen;
  sp.time_offset_sigma = cfg.joint.time_offset_sigma;
  return sp;
}

namespace {

/// Motions to start the refinement from (decideStart): RANSAC on short slices of the span
/// (T [s]) with gravity at its mean g_mean there (a slice is short enough that the mean
/// acceleration's share of the velocity change within it stays inside the gate), removing the
/// inliers of each motion found. Slices start at the span's beginning and at three later times:
/// a scan pattern sweeps the view, so that what the first instants see may be one large moving
/// object, with the world in view only later.
std::vector<Vec3> ransacStarts(const Rows& rows, double T, const Vec3& g_mean,
                               const StartDetectorParams& p) {
  const Eigen::Index n = rows.size();
  std::mt19937_64 rng(0x5eed ^ static_cast<std::size_t>(n));
  std::vector<Vec3> starts;
  const double ransac_gate = 2.0 * p.gate;
  constexpr double kSlice = 0.015;  // [s]
  constexpr std::size_t kSlicePoints = 200;
  // The pool's equations side by side (its candidates are counted 64 times each), with the
  // gravity term t w^T g_mean, which RANSAC holds, computed once.
  std::vector<Eigen::Index> pool, unexplained;
  pool.reserve(static_cast<std::size_t>(n));
  unexplained.reserve(static_cast<std::size_t>(n));
  Eigen::ArrayXd pe(n), pwx(n), pwy(n), pwz(n), ptg(n);
  for (int slice = 0; slice < 4; ++slice) {
    const double t_s = T * slice / 4.0;
    pool.clear();
    for (Eigen::Index j = 0; j < n; ++j)
      if (rows(j, Rows::T) >= t_s &&
          (rows(j, Rows::T) <= t_s + kSlice || pool.size() < kSlicePoints))
        pool.push_back(j);
    for (int h = 0; h < p.max_hypotheses && pool.size() >= 10; ++h) {
      const Eigen::Index m = static_cast<Eigen::Index>(pool.size());
      for (Eigen::Index k = 0; k < m; ++k) {
        const Eigen::Index j = pool[static_cast<std::size_t>(k)];
        pe[k] = rows(j, Rows::E);
        pwx[k] = rows(j, Rows::WX);
        pwy[k] = rows(j, Rows::WY);
        pwz[k] = rows(j, Rows::WZ);
        ptg[k] = rows(j, Rows::T) * rows.w(j).dot(g_mean);
      }
      const PoolArrays candidates{pe.data(), pwx.data(), pwy.data(), pwz.data(), ptg.data()};
      std::uniform_int_distribution<std::size_t> pick(0, pool.size() - 1);
      std::size_t best = 0;
      Vec3 best_v = Vec3::Zero();
      for (int it = 0; it < p.ransac_iterations; ++it) {
        Mat3 W;
        Vec3 e;
        for (int k = 0; k < 3; ++k) {
          const Eigen::Index j = pool[pick(rng)];
          const Vec3 w = rows.w(j);
          W.row(k) = w.transpose();
          e(k) = rows(j, Rows::E) + rows(j, Rows::T) * w.dot(g_mean);
        }
        if (std::abs(W.determinant()) < 1e-3) continue;
        const Vec3 v = -W.inverse() * e;
        // (Counted without the candidates that cannot beat the best: they change nothing.)
        const std::size_t count = countWithin(candidates, pool.size(), v.data(), ransac_gate, best);
        if (count > best) {
          best = count;
          best_v = v;
        }
      }
      if (best < std::max<std::size_t>(10, pool.size() / 20)) break;
      starts.push_back(best_v);
      // The pool's returns best_v leaves outside the gate (the gyro bias at its prior).
      unexplained.clear();
      for (std::size_t k = 0; k < pool.size(); ++k)
        if (!(std::abs(candidates.residual(k, best_v.x(), best_v.y(), best_v.z())) < ransac_gate))
          unexplained.push_back(pool[k]);
      pool.swap(unexplained);
    }
  }
  return starts;
}

/// The refinement of each start (ransacStarts) on the whole span, those that converge to the
/// same motion merged, by coverage of the view (then inliers), each with the rows it explains
/// (masks, in the same order).
std::vector<StartHypothesis> refineStarts(const std::vector<Vec3>& starts, const Rows& rows,
                                          const Rows& sub, const CoverageGrid& grid,
                                          RefineWork& work, const Vec3& g_mean, double T,
                                          double lever, const StartDetectorParams& p,
                                          std::vector<std::vector<std::uint8_t>>& masks) {
  std::vector<StartHypothesis> hypotheses;
  masks.clear();
  EarlyStates early;
  early.span = T;
  early.lever = lever;
  for (std::size_t i_start = 0; i_start < starts.size(); ++i_start) {
    const Vec3& v0 = starts[i_start];
    // The same motion found again in another slice converges to the same hypothesis: refine it
    // once (slices see one motion within the mean acceleration times their spacing).
    bool seen = false;
    for (std::size_t j = 0; j < i_start && !seen; ++j) seen = (starts[j] - v0).norm() < p.gate;
    for (const StartHypothesis& o : hypotheses) seen = seen || (o.v_b0 - v0).norm() < p.gate;
    if (seen) continue;
    std::vector<std::uint8_t> mask;
    // A refinement that joins an earlier one's path ends as that one did: nothing new.
    std::optional<StartHypothesis> first =
        refine(rows, sub, grid, work, v0, g_mean, false, p, &mask, 4.0, &early);
    if (!first) continue;
    StartHypothesis h = *first;
    // Gravity is what the refinement finds it to be. A fit that needs one far from 9.81 m/s^2
    // is tried again with gravity held near the mean specific force (a motion of the platform
    // cannot need more than its mean acceleration over the span); if that does not fit either,
    // it is not a motion of the platform.
    if (h.v_b0.allFinite() && std::abs(h.g_b0.norm() - kGravity) > p.max_gravity_error)
      h = *refine(rows, sub, grid, work, v0, g_mean, false, p, &mask, 0.5);
    if (h.inliers < 10 || !h.v_b0.allFinite()) continue;
    // Kept either way: an implausible motion is never chosen, but its returns still show that
    // something else moves coherently (a contender in decideStart).
    h.plausible_gravity = std::abs(h.g_b0.norm() - kGravity) <= p.max_gravity_error;
    bool merged = false;
    for (std::size_t o = 0; o < hypotheses.size(); ++o) {
      if ((hypotheses[o].v_b0 - h.v_b0).norm() < 2.0 * p.gate) {
        if (h.coverage > hypotheses[o].coverage) {
          hypotheses[o] = h;
          masks[o] = mask;
        }
        merged = true;
        break;
      }
    }
    if (!merged) {
      hypotheses.push_back(h);
      masks.push_back(std::move(mask));
    }
  }
  std::vector<std::size_t> order(hypotheses.size());
  for (std::size_t j = 0; j < order.size(); ++j) order[j] = j;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const StartHypothesis &ha = hypotheses[a], &hb = hypotheses[b];
    return ha.coverage != hb.coverage ? ha.coverage > hb.coverage : ha.inliers > hb.inliers;
  });
  {
    std::vector<StartHypothesis> hs;
    std::vector<std::vector<std::uint8_t>> ms;
    for (std::size_t j : order) {
      hs.push_back(hypotheses[j]);
      ms.push_back(std::move(masks[j]));
    }
    hypotheses.swap(hs);
    masks.swap(ms);
  }
  return hypotheses;
}

/// What the ground says of hypothesis b (StartDetectorParams::ground_share): how many returns
/// were taken as the ground (0: too few below the sensor to tell), the share of them b
/// explains, and the other hypothesis that explains most of the rest with that share.
struct GroundVerdict {
  std::size_t returns = 0;
  double chosen_share = 1;
  std::size_t other = 0;
  double other_share = 0;
};
GroundVerdict groundVerdict(const Rows& rows, const std::vector<double>& range, const Vec3& p_bl,
                            const std::vector<StartHypothesis>& hypotheses,
                            const std::vector<std::vector<std::uint8_t>>& masks, std::size_t b,
                            const StartDetectorParams& p) {
  GroundVerdict out;
  const Vec3 up = -hypotheses[b].g_b0.normalized();
  if (!up.allFinite()) return out;
  // Heights above the sensor's origin in b0 (the span's motion moves them by |v_z| T at most).
  std::vector<std::pair<double, std::size_t>> height;
  height.reserve(range.size());
  for (std::size_t j = 0; j < range.size(); ++j)
    if (range[j] > 0)
      height.emplace_back(range[j] * up.dot(rows.w(static_cast<Eigen::Index>(j))) + up.dot(p_bl),
                          j);
  constexpr std::size_t kFewest = 30;
  const std::size_t n =
      static_cast<std::size_t>(p.ground_share * static_cast<double>(height.size()));
  if (n < kFewest) return out;
  std::nth_element(height.begin(), height.begin() + static_cast<std::ptrdiff_t>(n - 1),
                   height.end());
  if (!(height[n - 1].first < -p.ground_depth)) return out;  // the lowest are not below
  std::size_t chosen = 0;
  std::vector<std::size_t> others(hypotheses.size(), 0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t j = height[i].second;
    if (masks[b][j] != 0) {
      ++chosen;
      continue;
    }
    for (std::size_t h = 0; h < hypotheses.size(); ++h)
      if (h != b && masks[h][j] != 0) ++others[h];
  }
  out.returns = n;
  out.chosen_share = static_cast<double>(chosen) / static_cast<double>(n);
  for (std::size_t h = 0; h < hypotheses.size(); ++h)
    if (h != b && static_cast<double>(others[h]) / static_cast<double>(n) > out.other_share) {
      out.other = h;
      out.other_share = static_cast<double>(others[h]) / static_cast<double>(n);
    }
  return out;
}

}  // namespace

StartDecision decideStart(const std::vector<ImuSample>& imu, std::size_t k_first,
                          std::size_t k_last, const std::vector<StartPoint>& points,
                          const Extrinsics& extrinsics, const Vec3& b_g_prior,
                          const StartDetectorParams& p,
                          const std::vector<detail::ImuExtraNoise>* extra) {
  StartDecision out;
  if (k_last <= k_first || k_last >= imu.size()) {
    out.message = "no IMU samples over the start of the window";
    return out;
  }
  const double t_ref = imu[k_first].t;
  // Strapdown integration in b0 over the span, with the estimator's own integrator (cubic
  // interpolation of the IMU and Simpson's rule: a vibrating platform needs them). It integrates
  // with a gravity, so with the world w = b0 and a start at rest the velocity it gives is
  // v(t) = C(t) + g_w t, from which C(t) follows.
  const std::vector<ImuSample> span(
      imu.begin() + static_cast<std::ptrdiff_t>(k_first > 0 ? k_first - 1 : k_first),
      imu.begin() + static_cast<std::ptrdiff_t>(std::min(imu.size(), k_last + 3)));
  const std::size_t j0 = k_first > 0 ? 1 : 0;  // the window start in `span`
  const Vec3 g_w(0, 0, -kGravity);
  const double T = imu[k_last].t - t_ref;
  FilterState x0;
  x0.t = t_ref;
  x0.b_g = b_g_prior;
  std::vector<FilterState> at;  // the state at each sample of the span
  at.reserve(k_last - k_first + 1);
  at.push_back(x0);
  for (std::size_t i = 1; i <= k_last - k_first; ++i)
    at.push_back(DopplerInertialFilter::propagate(at.back(), span, j0 + i - 1));
  const Vec3 g_mean = -(at.back().v_w - g_w * T) / T;  // exact at rest, off by the mean
                                                       // acceleration otherwise
  detail::RestEvidenceParams rp;
  rp.gyro_sigma = p.gyro_sigma;
  rp.accel_sigma = p.accel_sigma;
  rp.gyro_bias_prior = b_g_prior;
  rp.gyro_bias_sigma = p.gyro_bias_sigma;
  rp.accel_bias_bound = p.accel_bias_bound;
  out.imu_rest = detail::imuRestEvidence(imu, k_first, k_last + 1, rp, extra);
  out.imu_still = out.imu_rest.still;

  // Every return as a linear equation: the returns of the span with their interval, then the
  // returns of each interval at once, from its motion's polynomials (in time order, the returns
  // of an interval are consecutive).
  std::vector<std::size_t> interval;
  std::vector<double> r_t, r_tau, r_dx, r_dy, r_dz, r_z;
  for (auto* v : {&r_t, &r_tau, &r_dx, &r_dy, &r_dz, &r_z}) v->reserve(points.size());
  std::vector<Vec3> d_l;  // the directions in the LiDAR frame, for the coverage grid
  d_l.reserve(points.size());
  std::vector<double> range;  // for the ground check
  range.reserve(points.size());
  for (std::size_t j = 1; j < points.size(); ++j)
    if (!(points[j].t >= points[j - 1].t))
      throw std::invalid_argument("decideStart: return " + std::to_string(j) +
                                  " is not in time order");
  std::size_t i = 0;
  for (const StartPoint& sp : points) {
    if (sp.t < 0 || sp.t > T) continue;
    while (i + 1 < at.size() - 1 && imu[k_first + i + 1].t - t_ref <= sp.t) ++i;
    interval.push_back(i);
    r_t.push_back(sp.t);
    r_tau.push_back(sp.t - (imu[k_first + i].t - t_ref));
    r_dx.push_back(sp.d_l.x());
    r_dy.push_back(sp.d_l.y());
    r_dz.push_back(sp.d_l.z());
    r_z.push_back(sp.doppler);
    d_l.push_back(sp.d_l);
    range.push_back(sp.range);
  }
  const Eigen::Index n = static_cast<Eigen::Index>(d_l.size());
  if (n < 10) {
    out.message = "fewer than 10 usable LiDAR returns at the start of the window";
    return out;
  }
  Rows rows;
  rows.resize(n);
  std::vector<IntervalMotion> motion;
  motion.reserve(at.size() - 1);
  for (std::size_t k = 0; k + 1 < at.size(); ++k)
    motion.push_back(intervalMotion(span, j0 + k, at[k], imu[k_first + k].t - t_ref));
  for (std::size_t begin = 0; begin < d_l.size();) {
    const std::size_t k = interval[begin];
    std::size_t end = begin + 1;
    while (end < d_l.size() && interval[end] == k) ++end;
    const ReturnArrays in{r_t.data() + begin,  r_tau.data() + begin, r_dx.data() + begin,
                          r_dy.data() + begin, r_dz.data() + begin,  r_z.data() + begin};
    intervalEquations(motion[k], extrinsics, in, end - begin,
                      RowOutputs(rows, static_cast<Eigen::Index>(begin)));
    begin = end;
  }
  // The returns' directions must constrain a 3-D velocity at all.
  Mat3 info = Mat3::Zero();
  for (Eigen::Index j = 0; j < n; ++j) {
    const Vec3 w = rows.w(j);
    info.noalias() += w * w.transpose();
  }
  info /= p.doppler_sigma * p.doppler_sigma;
  const double weakest = Eigen::SelfAdjointEigenSolver<Mat3>(info).eigenvalues()(0);
  if (!(weakest >= p.min_info_eigen)) {
    out.kind = StartDecision::Kind::Degenerate;
    out.message = "the point directions do not constrain the velocity (weakest information " +
                  std::to_string(weakest) + " < " + std::to_string(p.min_info_eigen) +
                  " 1/(m/s)^2)";
    return out;
  }
  const CoverageGrid grid(d_l);
  const Rows sub = Rows::every(rows, 3);
  RefineWork work(n);

  // Hypotheses: motions found by RANSAC, refined on the whole span.
  std::vector<std::vector<std::uint8_t>> masks;  // the rows each hypothesis explains
  out.hypotheses = refineStarts(ransacStarts(rows, T, g_mean, p), rows, sub, grid, work, g_mean, T,
                                extrinsics.p_bl.norm(), p, masks);
  auto speed = [](const StartHypothesis& h) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2f", h.v_b0.norm());
    return std::string(buf);
  };
  auto percent = [](double x) { return std::to_string(static_cast<int>(std::lround(100 * x))); };
  const double best_coverage = out.hypotheses.empty() ? 0.0 : out.hypotheses.front().coverage;

  // The IMU at rest: rest (velocity held at zero) wins if enough of the view supports it.
  if (out.imu_still) {
    StartHypothesis rest = *refine(rows, sub, grid, work, Vec3::Zero(), g_mean, true, p);
    rest.rest = true;
    if (rest.inliers >= 10 && rest.coverage >= p.rest_coverage_ratio * best_coverage) {
      out.kind = StartDecision::Kind::Rest;
      out.chosen = rest;
      return checkConditioning(out, p);
    }
    out.kind = StartDecision::Kind::Ambiguous;
    out.message = out.hypotheses.empty()
                      ? std::string("the IMU shows rest but few LiDAR returns agree with it")
                      : "the IMU shows rest but the Doppler of the returns shows motion (" +
                            speed(out.hypotheses.front()) + " m/s over " + percent(best_coverage) +
                            " % of the view, rest over " + percent(rest.coverage) +
                            " %): a moving object may fill the view";
    return out;
  }
  if (out.hypotheses.empty()) {
    out.message = "no motion is consistent with the LiDAR returns at the start of the window";
    return out;
  }
  // The clock offset's columns, made when a motion is fitted with the offset (only then).
  std::optional<OffsetColumns> offset_columns;
  auto columns = [&]() -> const OffsetColumns& {
    if (!offset_columns)
      offset_columns = offsetColumns(rows, span, j0, at, interval, r_tau, extrinsics, t_ref);
    return *offset_columns;
  };
  const bool with_offset = p.time_offset_sigma > 0;
  // The best plausible motion, and the strongest other one counted on the returns the best does
  // not explain (two fits of one motion that differ a little share their returns: no contender).
  std::size_t b = 0;
  while (b < out.hypotheses.size() && !out.hypotheses[b].plausible_gravity) ++b;
  if (b == out.hypotheses.size() && with_offset) {
    // An undeclared clock offset bends the velocity's change over the span by the acceleration's
    // change times the offset, which a gravity far from 9.81 m/s^2 may absorb: each motion again,
    // with the offset free.
    for (std::size_t j = 0; j < out.hypotheses.size(); ++j) {
      std::vector<std::uint8_t> mask;
      const StartHypothesis h =
          refineOffset(rows, columns(), grid, work, out.hypotheses[j], g_mean, 4.0, 6, p, mask);
      if (!h.plausible_gravity || h.inliers < 10 || !h.v_b0.allFinite()) continue;
      out.hypotheses[j] = h;
      masks[j] = std::move(mask);
    }
    b = 0;
    while (b < out.hypotheses.size() && !out.hypotheses[b].plausible_gravity) ++b;
  }
  if (b == out.hypotheses.size()) {
    out.message =
        "no motion with a plausible gravity is consistent with the LiDAR returns at "
        "the start of the window";
    return out;
  }
  if (with_offset && !out.hypotheses[b].rest && out.hypotheses[b].time_offset_sigma == 0) {
    // The chosen motion with the clock offset: two Gauss-Newton steps from its fit (the equations
    // are linear in the offset but for its product with the motion's change: the first step
    // takes the offset, the second the few per cent left; with one, the filter's smoothing
    // needed more iterations than the second step costs).
    std::vector<std::uint8_t> mask;
    const StartHypothesis h =
        refineOffset(rows, columns(), grid, work, out.hypotheses[b], g_mean, 4.0, 2, p, mask);
    if (h.plausible_gravity && h.inliers >= 10 && h.v_b0.allFinite()) {
      out.hypotheses[b] = h;
      masks[b] = std::move(mask);
    }
  }
  const StartHypothesis& best = out.hypotheses[b];
  double contender = 0;
  std::size_t c = b;
  for (std::size_t j = 0; j < out.hypotheses.size(); ++j) {
    if (j == b) continue;
    const std::vector<std::uint8_t>&mj = masks[j], &mb = masks[b];
    const double cov = grid.coverage([&](std::size_t r) { return mj[r] != 0 && mb[r] == 0; });
    if (cov > contender) {
      contender = cov;
      c = j;
    }
  }
  if (c != b && contender >= p.ambiguity_ratio * best.coverage &&
      contender >= p.min_contender_coverage) {
    out.kind = StartDecision::Kind::Ambiguous;
    out.message = "two motions fit the LiDAR returns (" + speed(best) + " and " +
                  speed(out.hypotheses[c]) + " m/s over " + percent(best.coverage) + " and " +
                  percent(contender) + " % of the view): a large moving object may fill the view";
    return out;
  }
  // The ground does not move: a motion that leaves the lowest returns to another one is a
  // large object filling the view (a bus, a truck alongside), with the world seen on the ground
  // only. Its share of the view says nothing then.
  if (const GroundVerdict ground =
          groundVerdict(rows, range, extrinsics.p_bl, out.hypotheses, masks, b, p);
      ground.returns > 0 && ground.chosen_share <= p.ground_explained_max &&
      ground.other_share >= p.ground_other_min) {
    out.kind = StartDecision::Kind::Ambiguous;
    out.message = "the motion over most of the view (" + speed(best) + " m/s over " +
                  percent(best.coverage) + " % of it) leaves the ground to another one (" +
                  speed(out.hypotheses[ground.other]) + " m/s explains " +
                  percent(ground.other_share) + " % of the " + std::to_string(ground.returns) +
                  " lowest returns, it " + percent(ground.chosen_share) +
                  " %): a large moving object may fill the view";
    return out;
  }
  out.chosen = best;
  out.kind = best.rest ? StartDecision::Kind::Rest : StartDecision::Kind::Moving;
  return checkConditioning(out, p);
}

}  // namespace freeinit
