#include <freeinit/doppler_inertial_filter.h>
#include <freeinit/rotation.h>
#include <freeinit/start_detector.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

namespace freeinit {
namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

/// Chi-square quantile (Wilson-Hilferty) for `dof` degrees of freedom at the standard-normal
/// quantile z.
double chi2Quantile(double dof, double z) {
  const double a = 2.0 / (9.0 * dof);
  return dof * std::pow(1.0 - a + z * std::sqrt(a), 3);
}


/// A return as a linear equation in theta = (v_b0, g_b0): e = a^T theta + noise.
struct Row {
  Vec3 w = Vec3::Zero();  ///< direction in b0
  Vec3 u = Vec3::Zero();  ///< direction in b(t)
  Vec3 pxu = Vec3::Zero();  ///< p_bl x u (lever arm sensitivity to the gyro bias)
  Mat3 R_t = Mat3::Identity();  ///< R_0t
  Vec3 C_t = Vec3::Zero();
  double t = 0;
  double e = 0;
  Vec3 d_l = Vec3::Zero();
  double residual(const Vec3& v, const Vec3& g) const { return e + w.dot(v) + t * w.dot(g); }
  Vec6 a() const {
    Vec6 r;
    r << -w, -t * w;
    return r;
  }
};

/// Field-of-view cells of the returns: a grid over the observed azimuth/elevation extent.
class CoverageGrid {
 public:
  explicit CoverageGrid(const std::vector<Row>& rows) {
    for (const Row& r : rows) {
      const double az = std::atan2(r.d_l.y(), r.d_l.x());
      const double el = std::asin(std::clamp(r.d_l.z(), -1.0, 1.0));
      az_lo_ = std::min(az_lo_, az);
      az_hi_ = std::max(az_hi_, az);
      el_lo_ = std::min(el_lo_, el);
      el_hi_ = std::max(el_hi_, el);
    }
    cell_.reserve(rows.size());
    totals_.assign(kAz * kEl, 0);
    for (const Row& r : rows) {
      const int c = cellOf(r.d_l);
      cell_.push_back(c);
      ++totals_[static_cast<std::size_t>(c)];
    }
  }
  /// Share of the occupied cells (at least 2 returns) in which most returns are inliers.
  double coverage(const std::vector<bool>& inlier) const {
    std::vector<int> in(totals_.size(), 0);
    for (std::size_t i = 0; i < cell_.size(); ++i)
      if (inlier[i]) ++in[static_cast<std::size_t>(cell_[i])];
    int occupied = 0, supported = 0;
    for (std::size_t c = 0; c < totals_.size(); ++c) {
      if (totals_[c] < 2) continue;
      ++occupied;
      if (2 * in[c] > totals_[c]) ++supported;
    }
    return occupied > 0 ? static_cast<double>(supported) / occupied : 0.0;
  }

 private:
  static constexpr int kAz = 16, kEl = 8;
  int cellOf(const Vec3& d) const {
    const double az = std::atan2(d.y(), d.x());
    const double el = std::asin(std::clamp(d.z(), -1.0, 1.0));
    const auto bin = [](double x, double lo, double hi, int n) {
      if (!(hi > lo)) return 0;
      return std::clamp(static_cast<int>((x - lo) / (hi - lo) * n), 0, n - 1);
    };
    return bin(az, az_lo_, az_hi_, kAz) * kEl + bin(el, el_lo_, el_hi_, kEl);
  }
  double az_lo_ = 1e9, az_hi_ = -1e9, el_lo_ = 1e9, el_hi_ = -1e9;
  std::vector<int> cell_;
  std::vector<int> totals_;
};

/// IRLS (Cauchy) refinement of theta = (v_b0, g_b0, db_g) from a start, with a weak gravity
/// prior and the gyro-bias prior. A gyro-bias error db turns the body-frame velocity by
/// -t db x v_b(t) over the span and the lever-arm velocity by -db x p_bl, so that the Doppler of a
/// return changes by (p_bl x u - t v_b(t) x u)^T db (first order; the effect of db on the
/// integrated specific force, t^2 |f| db, is neglected). At speed this is what limits the gravity
/// of so short a span: it must be in its covariance.
/// `at_rest`: the rest hypothesis, velocity zero and gravity the mean specific force (the moving
/// objects of a static start must not bend either: only the gyro-bias correction is fitted).
/// `inliers` (if given) receives which rows the refined motion explains; `g_sigma_max` [m/s^2]
/// caps the gravity prior's std.
StartHypothesis refine(const std::vector<Row>& rows, const CoverageGrid& grid, const Vec3& v_start,
                       const Vec3& g_prior, bool at_rest, const StartDetectorParams& p,
                       std::vector<bool>* inliers = nullptr, double g_sigma_max = 4.0) {
  using Vec9 = Eigen::Matrix<double, 9, 1>;
  using Mat9 = Eigen::Matrix<double, 9, 9>;
  Vec3 v = v_start, g = g_prior, db = Vec3::Zero();
  const double inv_r = 1.0 / (p.doppler_sigma * p.doppler_sigma);
  // Gravity prior: the mean specific force is within a few m/s^2 of it on any real platform in
  // motion; at rest it is gravity minus the accelerometer bias, held.
  const double g_prior_var = at_rest ? 1e-12 : g_sigma_max * g_sigma_max;
  const double bg_prior_var = p.gyro_bias_sigma * p.gyro_bias_sigma;
  auto rowOf = [&](const Row& r, Vec9& a) {
    const Vec3 v_b = r.R_t.transpose() * (v + r.C_t + g * r.t);
    a << -r.w, -r.t * r.w, r.pxu - r.t * v_b.cross(r.u);
  };
  auto residual = [&](const Row& r, const Vec9& a) {
    return r.e - a.head<6>().dot((Vec6() << v, g).finished()) - a.tail<3>().dot(db);
  };
  Mat9 A = Mat9::Zero();
  // (Cauchy scale [m/s], gravity prior std [m/s^2]) per iteration. Gravity is held near its prior
  // at first: free from the start, it would let the returns of a large moving object that are
  // consistent with the start only along some directions pull the motion towards theirs.
  const std::vector<std::pair<double, double>> schedule = {
      {0.3, 0.5}, {0.3, 1.0}, {0.2, 4.0}, {0.15, 4.0}, {0.1, 4.0}, {0.1, 4.0}, {0.1, 4.0}};
  Vec9 a;
  for (std::size_t iteration = 0; iteration < schedule.size(); ++iteration) {
    const auto [c, g_sigma] = schedule[iteration];
    // The first iterations, which only find the inliers, take every third return (weighted
    // three times), the last ones every return.
    const std::size_t step = iteration + 3 < schedule.size() && rows.size() > 1500 ? 3 : 1;
    const double g_var = at_rest ? g_prior_var : std::min(g_sigma * g_sigma, g_prior_var);
    A.setZero();
    Vec9 b = Vec9::Zero();
    A.block<3, 3>(3, 3).diagonal().setConstant(1.0 / g_var);
    b.segment<3>(3) = g_prior / g_var;
    A.block<3, 3>(6, 6).diagonal().setConstant(1.0 / bg_prior_var);
    if (at_rest) {
      A.topLeftCorner<3, 3>().diagonal().setConstant(1e12);
      b.head<3>() = v_start * 1e12;
    }
    for (std::size_t i = 0; i < rows.size(); i += step) {
      const Row& r = rows[i];
      rowOf(r, a);
      const double res = residual(r, a);
      const double u = res / std::max(c, 3.0 * p.doppler_sigma);
      const double w = static_cast<double>(step) * inv_r / ((1.0 + u * u) * (1.0 + u * u));
      A.selfadjointView<Eigen::Lower>().rankUpdate(a, w);
      // Linear in theta given the row: e = a^T theta (the db column depends on v, g: iterate).
      b.noalias() += w * r.e * a;
    }
    const Vec9 theta = A.ldlt().solve(b);
    if (!theta.allFinite()) break;
    v = theta.head<3>();
    g = theta.segment<3>(3);
    db = theta.tail<3>();
  }
  StartHypothesis h;
  h.v_b0 = v;
  h.g_b0 = g;
  std::vector<bool> inl(rows.size(), false);
  double ss = 0;
  Mat9 info = Mat9::Zero();
  info.block<3, 3>(3, 3).diagonal().setConstant(1.0 / g_prior_var);
  info.block<3, 3>(6, 6).diagonal().setConstant(1.0 / bg_prior_var);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    rowOf(rows[i], a);
    const double res = residual(rows[i], a);
    if (std::abs(res) > p.gate) continue;
    inl[i] = true;
    ++h.inliers;
    ss += res * res;
    info.noalias() += inv_r * a * a.transpose();
  }
  h.residual_rms = h.inliers > 0 ? std::sqrt(ss / static_cast<double>(h.inliers)) : 0.0;
  const double k = std::max(1.0, h.residual_rms / p.doppler_sigma);
  const Mat9 cov = info.ldlt().solve(Mat9::Identity()) * k * k;
  h.cov = cov.topLeftCorner<6, 6>();
  h.coverage = grid.coverage(inl);
  if (inliers != nullptr) *inliers = std::move(inl);
  h.rest = v.norm() < p.max_speed;
  h.min_info_eigen = Eigen::SelfAdjointEigenSolver<Mat3>(info.topLeftCorner<3, 3>()).eigenvalues()(0);
  return h;
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

bool imuShowsRest(const std::vector<ImuSample>& imu, std::size_t begin, std::size_t end,
                  double gyro_sigma, double accel_sigma) {
  if (end <= begin + 2 || end > imu.size()) return false;
  const double n = static_cast<double>(end - begin);
  Vec3 mg = Vec3::Zero(), ma = Vec3::Zero();
  for (std::size_t i = begin; i < end; ++i) {
    mg += imu[i].gyro;
    ma += imu[i].accel;
  }
  mg /= n;
  ma /= n;
  double sg = 0, sa = 0;
  for (std::size_t i = begin; i < end; ++i) {
    sg += (imu[i].gyro - mg).squaredNorm();
    sa += (imu[i].accel - ma).squaredNorm();
  }
  // Spread about the mean: chi-square with 3 (n - 1) dof for white noise; a factor 1.5 on the
  // variance leaves room for a datasheet that is a little optimistic.
  const double limit = 1.5 * chi2Quantile(3.0 * (n - 1.0), 3.09);
  return sg / (gyro_sigma * gyro_sigma) < limit && sa / (accel_sigma * accel_sigma) < limit;
}

StartDecision decideStart(const std::vector<ImuSample>& imu, std::size_t k0, std::size_t k1,
                          const std::vector<StartPoint>& points, const Extrinsics& extrinsics,
                          const Vec3& b_g_prior, const StartDetectorParams& p) {
  StartDecision out;
  if (k1 <= k0 || k1 >= imu.size()) {
    out.message = "no IMU samples over the start of the window";
    return out;
  }
  const double t_ref = imu[k0].t;
  // Strapdown integration in b0 over the span, with the estimator's own integrator (cubic
  // interpolation of the IMU and Simpson's rule: a vibrating platform needs them). It integrates
  // with a gravity, so with the world w = b0 and a start at rest the velocity it gives is
  // v(t) = C(t) + g_w t, from which C(t) follows.
  const std::vector<ImuSample> span(imu.begin() + static_cast<std::ptrdiff_t>(k0 > 0 ? k0 - 1 : k0),
                                    imu.begin() + static_cast<std::ptrdiff_t>(
                                                      std::min(imu.size(), k1 + 3)));
  const std::size_t j0 = k0 > 0 ? 1 : 0;  // the window start in `span`
  const Vec3 g_w(0, 0, -kGravity);
  const double T = imu[k1].t - t_ref;
  FilterState x0;
  x0.t = t_ref;
  x0.b_g = b_g_prior;
  std::vector<FilterState> at;  // the state at each sample of the span
  at.reserve(k1 - k0 + 1);
  at.push_back(x0);
  for (std::size_t i = 1; i <= k1 - k0; ++i)
    at.push_back(DopplerInertialFilter::propagate(at.back(), span, j0 + i - 1));
  const Vec3 g_mean = -(at.back().v_w - g_w * T) / T;  // exact at rest, off by the mean
                                                        // acceleration otherwise
  out.imu_still = imuShowsRest(imu, k0, k1 + 1, p.gyro_sigma, p.accel_sigma);

  // Every return as a linear equation.
  std::vector<Row> rows;
  rows.reserve(points.size());
  std::size_t i = 0;
  for (const StartPoint& sp : points) {
    if (sp.t < 0 || sp.t > T) continue;
    while (i + 1 < at.size() - 1 && imu[k0 + i + 1].t - t_ref <= sp.t) ++i;
    const double tau = sp.t - (imu[k0 + i].t - t_ref);
    const FilterState xt = DopplerInertialFilter::integrate(at[i], span, j0 + i, tau);
    Vec3 gyro, accel;
    DopplerInertialFilter::interpolateImu(span, t_ref + sp.t, gyro, accel);
    gyro -= b_g_prior;
    const Mat3 R_t = xt.R_wb;
    const Vec3 C_t = xt.v_w - g_w * sp.t;
    Row r;
    const Vec3 u = extrinsics.R_bl * sp.d_l;
    r.u = u;
    r.pxu = extrinsics.p_bl.cross(u);
    r.R_t = R_t;
    r.C_t = C_t;
    r.w = R_t * u;
    r.t = sp.t;
    r.d_l = sp.d_l;
    r.e = sp.doppler + u.dot(gyro.cross(extrinsics.p_bl)) + r.w.dot(C_t);
    rows.push_back(r);
  }
  if (rows.size() < 10) {
    out.message = "fewer than 10 usable LiDAR returns at the start of the window";
    return out;
  }
  // The returns' directions must constrain a 3-D velocity at all.
  Mat3 info = Mat3::Zero();
  for (const Row& r : rows) info.noalias() += r.w * r.w.transpose();
  info /= p.doppler_sigma * p.doppler_sigma;
  const double weakest = Eigen::SelfAdjointEigenSolver<Mat3>(info).eigenvalues()(0);
  if (!(weakest >= p.min_info_eigen)) {
    out.kind = StartDecision::Kind::Degenerate;
    out.message = "the point directions do not constrain the velocity (weakest information " +
                  std::to_string(weakest) + " < " + std::to_string(p.min_info_eigen) +
                  " 1/(m/s)^2)";
    return out;
  }
  const CoverageGrid grid(rows);

  // Hypotheses: RANSAC on short slices of the span (gravity at its mean there; a slice is short
  // enough that the mean acceleration's share of the velocity change within it stays inside the
  // gate), removing the inliers of each hypothesis found. Slices start at the span's beginning
  // and at three later times: a scan pattern sweeps the view, so that what the first instants
  // see may be one large moving object, with the world in view only later.
  std::mt19937_64 rng(0x5eed ^ rows.size());
  std::vector<Vec3> starts;
  const double ransac_gate = 2.0 * p.gate;
  constexpr double kSlice = 0.015;  // [s]
  constexpr std::size_t kSlicePoints = 200;
  for (int slice = 0; slice < 4; ++slice) {
    const double t_s = T * slice / 4.0;
    std::vector<std::size_t> pool;
    for (std::size_t j = 0; j < rows.size(); ++j)
      if (rows[j].t >= t_s && (rows[j].t <= t_s + kSlice || pool.size() < kSlicePoints))
        pool.push_back(j);
    for (int h = 0; h < p.max_hypotheses && pool.size() >= 10; ++h) {
      std::uniform_int_distribution<std::size_t> pick(0, pool.size() - 1);
      std::size_t best = 0;
      Vec3 best_v = Vec3::Zero();
      for (int it = 0; it < p.ransac_iterations; ++it) {
        Mat3 W;
        Vec3 e;
        for (int k = 0; k < 3; ++k) {
          const Row& r = rows[pool[pick(rng)]];
          W.row(k) = r.w.transpose();
          e(k) = r.e + r.t * r.w.dot(g_mean);
        }
        if (std::abs(W.determinant()) < 1e-3) continue;
        const Vec3 v = -W.inverse() * e;
        std::size_t count = 0;
        for (std::size_t j : pool)
          if (std::abs(rows[j].residual(v, g_mean)) < ransac_gate) ++count;
        if (count > best) {
          best = count;
          best_v = v;
        }
      }
      if (best < std::max<std::size_t>(10, pool.size() / 20)) break;
      starts.push_back(best_v);
      std::vector<std::size_t> rest;
      for (std::size_t j : pool)
        if (std::abs(rows[j].residual(best_v, g_mean)) >= ransac_gate) rest.push_back(j);
      pool.swap(rest);
    }
  }
  // Refine each on the whole span; merge those that converge to the same motion.
  std::vector<std::vector<bool>> masks;  // the rows each hypothesis explains
  for (std::size_t i_start = 0; i_start < starts.size(); ++i_start) {
    const Vec3& v0 = starts[i_start];
    // The same motion found again in another slice converges to the same hypothesis: refine it
    // once (slices see one motion within the mean acceleration times their spacing).
    bool seen = false;
    for (std::size_t j = 0; j < i_start && !seen; ++j) seen = (starts[j] - v0).norm() < p.gate;
    for (const StartHypothesis& o : out.hypotheses)
      seen = seen || (o.v_b0 - v0).norm() < p.gate;
    if (seen) continue;
    std::vector<bool> mask;
    StartHypothesis h = refine(rows, grid, v0, g_mean, false, p, &mask);
    // Gravity is what the refinement finds it to be. A fit that needs one far from 9.81 m/s^2
    // is tried again with gravity held near the mean specific force (a motion of the platform
    // cannot need more than its mean acceleration over the span); if that does not fit either,
    // it is not a motion of the platform.
    if (h.v_b0.allFinite() && std::abs(h.g_b0.norm() - kGravity) > p.max_gravity_error)
      h = refine(rows, grid, v0, g_mean, false, p, &mask, 0.5);
    if (h.inliers < 10 || !h.v_b0.allFinite()) continue;
    // Kept either way: an implausible motion is never chosen, but its returns still show that
    // something else moves coherently (a contender, below).
    h.plausible_gravity = std::abs(h.g_b0.norm() - kGravity) <= p.max_gravity_error;
    bool merged = false;
    for (std::size_t o = 0; o < out.hypotheses.size(); ++o) {
      if ((out.hypotheses[o].v_b0 - h.v_b0).norm() < 2.0 * p.gate) {
        if (h.coverage > out.hypotheses[o].coverage) {
          out.hypotheses[o] = h;
          masks[o] = mask;
        }
        merged = true;
        break;
      }
    }
    if (!merged) {
      out.hypotheses.push_back(h);
      masks.push_back(std::move(mask));
    }
  }
  std::vector<std::size_t> order(out.hypotheses.size());
  for (std::size_t j = 0; j < order.size(); ++j) order[j] = j;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const StartHypothesis &ha = out.hypotheses[a], &hb = out.hypotheses[b];
    return ha.coverage != hb.coverage ? ha.coverage > hb.coverage : ha.inliers > hb.inliers;
  });
  {
    std::vector<StartHypothesis> hs;
    std::vector<std::vector<bool>> ms;
    for (std::size_t j : order) {
      hs.push_back(out.hypotheses[j]);
      ms.push_back(std::move(masks[j]));
    }
    out.hypotheses.swap(hs);
    masks.swap(ms);
  }
  auto speed = [](const StartHypothesis& h) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2f", h.v_b0.norm());
    return std::string(buf);
  };
  auto percent = [](double x) { return std::to_string(static_cast<int>(std::lround(100 * x))); };
  const double best_coverage = out.hypotheses.empty() ? 0.0 : out.hypotheses.front().coverage;

  // The IMU at rest: rest (velocity held at zero) wins if enough of the view supports it.
  if (out.imu_still) {
    StartHypothesis rest = refine(rows, grid, Vec3::Zero(), g_mean, true, p);
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
                            speed(out.hypotheses.front()) + " m/s over " +
                            percent(best_coverage) + " % of the view, rest over " +
                            percent(rest.coverage) + " %): a moving object may fill the view";
    return out;
  }
  if (out.hypotheses.empty()) {
    out.message = "no motion is consistent with the LiDAR returns at the start of the window";
    return out;
  }
  // The best plausible motion, and the strongest other one counted on the returns the best does
  // not explain (two fits of one motion that differ a little share their returns: no contender).
  std::size_t b = 0;
  while (b < out.hypotheses.size() && !out.hypotheses[b].plausible_gravity) ++b;
  if (b == out.hypotheses.size()) {
    out.message = "no motion with a plausible gravity is consistent with the LiDAR returns at "
                  "the start of the window";
    return out;
  }
  const StartHypothesis& best = out.hypotheses[b];
  double contender = 0;
  std::size_t c = b;
  for (std::size_t j = 0; j < out.hypotheses.size(); ++j) {
    if (j == b) continue;
    std::vector<bool> own(rows.size());
    for (std::size_t r = 0; r < rows.size(); ++r) own[r] = masks[j][r] && !masks[b][r];
    const double cov = grid.coverage(own);
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
  out.chosen = best;
  out.kind = best.rest ? StartDecision::Kind::Rest : StartDecision::Kind::Moving;
  return checkConditioning(out, p);
}

}  // namespace freeinit
