// The LiDAR data must be exactly consistent with the ground truth up to the injected noise:
// Doppler residuals of static points are N(0, doppler_sigma), ranges re-cast against the scene
// differ by N(0, range_sigma), and a least-squares LiDAR velocity from a short slice of points
// matches the true one.
#include <freeinit/sim/presets.h>
#include <freeinit/sim/scene.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

namespace freeinit::sim {
namespace {

/// LiDAR velocity in the LiDAR frame at time t: v_l = R_wl^T (v_w + R_wb (omega_b x p_bl)).
Vec3 trueLidarVelocity(const Recording& rec, double t) {
  const TruthState s = rec.truth(t);
  const Mat3 R_wl = s.R_wb * rec.extrinsics.R_bl;
  return R_wl.transpose() * (s.v_w + s.R_wb * s.omega_b.cross(rec.extrinsics.p_bl));
}

struct Stats {
  long n = 0;
  double sum = 0, sum2 = 0;
  void add(double x) {
    ++n;
    sum += x;
    sum2 += x * x;
  }
  double mean() const { return sum / static_cast<double>(n); }
  double std() const { return std::sqrt(sum2 / static_cast<double>(n) - mean() * mean()); }
};

Recording lidarRecording(const std::string& name, std::uint64_t seed, double duration, int points) {
  ScenarioConfig c = preset(name, seed);
  c.duration = duration;
  c.points_per_frame = points;
  return simulate(c);
}

void checkDoppler(const Recording& rec) {
  const double sigma = rec.config.doppler_sigma;
  Stats st;
  long n_all = 0, n_outlier = 0, n_dyn = 0, n_dyn_large = 0;
  for (std::size_t f = 0; f < rec.frames.size(); ++f) {
    const LidarFrame& fr = rec.frames[f];
    for (std::size_t i = 0; i < fr.points.size(); ++i) {
      const DopplerPoint& pt = fr.points[i];
      const PointLabel label = rec.labels[f][i];
      ++n_all;
      if (label == PointLabel::Outlier) {
        ++n_outlier;
        continue;
      }
      const double t = fr.stamp + static_cast<double>(pt.time_offset);
      const Vec3 d_l = pt.p_l.cast<double>().normalized();
      // Static point: doppler = -d_l^T v_l.
      const double residual = pt.doppler + d_l.dot(trueLidarVelocity(rec, t));
      if (label == PointLabel::Static) {
        st.add(residual);
      } else {
        ++n_dyn;
        if (std::abs(residual) > 5.0 * sigma) ++n_dyn_large;
      }
    }
  }
  std::printf(
      "%s: %ld points, static residual mean %.2e std %.5f, outliers %.4f, dynamic %.3f "
      "(%.2f of them > 5 sigma)\n",
      rec.config.name.c_str(), n_all, st.mean(), st.std(), static_cast<double>(n_outlier) / n_all,
      static_cast<double>(n_dyn) / n_all, static_cast<double>(n_dyn_large) / std::max(n_dyn, 1L));
  ASSERT_GT(st.n, 50000);
  // Sample std of N Gaussian samples: relative standard error 1/sqrt(2N) < 0.3 %; 10 % is ~30x.
  EXPECT_NEAR(st.std(), sigma, 0.1 * sigma);
  // Mean: standard error sigma/sqrt(N); 5 of them.
  EXPECT_LT(std::abs(st.mean()), 5.0 * sigma / std::sqrt(static_cast<double>(st.n)));
  // Outliers: Bernoulli(p = 0.01): std sqrt(p(1-p)/N); 5 of them.
  const double p = rec.config.outlier_ratio;
  EXPECT_NEAR(static_cast<double>(n_outlier) / n_all, p, 5.0 * std::sqrt(p * (1 - p) / n_all));
}

TEST(SimLidar, StaticDopplerResidualIsInjectedNoiseRotational) {
  const Recording rec = lidarRecording("dyna_04", 5, 1.0, 20000);
  checkDoppler(rec);
}

TEST(SimLidar, StaticDopplerResidualIsInjectedNoiseVehicular) {
  const Recording rec = lidarRecording("dyna_05", 6, 1.0, 20000);
  checkDoppler(rec);
}

TEST(SimLidar, DynamicPointsDoNotFitTheStaticModel) {
  const Recording rec = lidarRecording("dyna_06", 2, 0.5, 20000);
  long n = 0, n_dyn = 0, n_large = 0;
  for (std::size_t f = 0; f < rec.frames.size(); ++f) {
    for (std::size_t i = 0; i < rec.frames[f].points.size(); ++i) {
      ++n;
      if (rec.labels[f][i] != PointLabel::Dynamic) continue;
      ++n_dyn;
      const DopplerPoint& pt = rec.frames[f].points[i];
      const double t = rec.frames[f].stamp + static_cast<double>(pt.time_offset);
      const double r =
          pt.doppler + pt.p_l.cast<double>().normalized().dot(trueLidarVelocity(rec, t));
      if (std::abs(r) > 1.0) ++n_large;  // > 30 sigma
    }
  }
  // Cars move at 9-20 m/s mostly along the line of sight: most of their points are far off.
  EXPECT_GT(static_cast<double>(n_dyn) / n, 0.02);  // typically 4-12 % (seed dependent)
  EXPECT_GT(static_cast<double>(n_large) / n_dyn, 0.5);
}

// Re-casting each point's ray from the true LiDAR pose at the point's own time against the full
// (unculled) scene must give the measured range up to the injected N(0, range_sigma) noise. This
// also proves that the per-frame/per-line culling never drops a nearer primitive.
TEST(SimLidar, RangesMatchSceneUpToInjectedNoise) {
  for (const std::string name : {"dyna_04", "stat_01", "dyna_05"}) {
    const Recording rec = lidarRecording(name, 4, 0.3, 20000);
    Stats st;
    long gross = 0;
    for (const LidarFrame& fr : rec.frames) {
      for (const DopplerPoint& pt : fr.points) {
        const double t = fr.stamp + static_cast<double>(pt.time_offset);
        const TruthState s = rec.truth(t);
        const Mat3 R_wl = s.R_wb * rec.extrinsics.R_bl;
        const Vec3 p_wl = s.p_w + s.R_wb * rec.extrinsics.p_bl;
        const Vec3 p_l = pt.p_l.cast<double>();
        RayHit hit;
        ASSERT_TRUE(rec.scene->castRay(p_wl, R_wl * p_l.normalized(), t - rec.config.t0,
                                       rec.config.max_range + 1.0, hit));
        const double r = p_l.norm() - hit.range;
        if (std::abs(r) > 8.0 * rec.config.range_sigma) {
          ++gross;  // a float-rounded direction grazing an edge can switch surfaces
          continue;
        }
        st.add(r);
      }
    }
    std::printf("%s: %ld points, range residual mean %.2e std %.5f, gross %ld\n", name.c_str(),
                st.n, st.mean(), st.std(), gross);
    ASSERT_GT(st.n, 40000);
    EXPECT_LT(static_cast<double>(gross) / st.n, 1e-4);
    // 8-sigma clipping removes ~1e-15 of a Gaussian: std and mean are those of the noise.
    EXPECT_NEAR(st.std(), rec.config.range_sigma, 0.05 * rec.config.range_sigma);
    EXPECT_LT(std::abs(st.mean()), 5.0 * rec.config.range_sigma / std::sqrt(st.n));
  }
}

// Least squares over the static points of one 5 ms slice: doppler_i = -d_i^T v_l, v_l assumed
// constant. Bound per axis: 5 standard errors from sigma^2 (A^T A)^-1 plus the largest change of
// the largest change of the true v_l within half the slice (the constant-velocity model error)
// propagated through the estimator in the worst case.
void checkSliceVelocity(const std::string& name, double slice) {
  const Recording rec = lidarRecording(name, 8, 0.3, 60000);
  const LidarFrame& fr = rec.frames[1];
  for (double t_begin : {0.0, 0.03, 0.06}) {
    Eigen::Matrix3d AtA = Eigen::Matrix3d::Zero();
    Vec3 Atb = Vec3::Zero();
    double t_sum = 0;
    int n = 0;
    for (std::size_t i = 0; i < fr.points.size(); ++i) {
      const DopplerPoint& pt = fr.points[i];
      if (pt.time_offset < t_begin || pt.time_offset >= t_begin + slice) continue;
      if (rec.labels[1][i] != PointLabel::Static) continue;
      const Vec3 d = pt.p_l.cast<double>().normalized();
      AtA += d * d.transpose();
      Atb += d * (-static_cast<double>(pt.doppler));
      t_sum += pt.time_offset;
      ++n;
    }
    ASSERT_GT(n, 500);
    const Vec3 v_est = AtA.ldlt().solve(Atb);
    const double t_mid = fr.stamp + t_sum / n;
    const Vec3 v_true = trueLidarVelocity(rec, t_mid);
    const Eigen::Matrix3d cov = rec.config.doppler_sigma * rec.config.doppler_sigma * AtA.inverse();
    double model = 0;
    for (double dt = -0.5 * slice; dt <= 0.5 * slice + 1e-12; dt += 0.1 * slice) {
      model = std::max(model, (trueLidarVelocity(rec, fr.stamp + t_begin + 0.5 * slice + dt) -
                               trueLidarVelocity(rec, fr.stamp + t_begin + 0.5 * slice))
                                  .norm());
    }
    // Worst-case propagation of the model error through the estimator:
    // |delta v_k| <= sum_i |[(A^T A)^-1 d_i]_k| * model, since |d_i^T delta v_l(t_i)| <= model.
    const Eigen::Matrix3d AtA_inv = AtA.inverse();
    Vec3 leverage = Vec3::Zero();
    for (std::size_t i = 0; i < fr.points.size(); ++i) {
      const DopplerPoint& pt = fr.points[i];
      if (pt.time_offset < t_begin || pt.time_offset >= t_begin + slice) continue;
      if (rec.labels[1][i] != PointLabel::Static) continue;
      leverage += (AtA_inv * pt.p_l.cast<double>().normalized()).cwiseAbs();
    }
    const Vec3 err = v_est - v_true;
    std::printf("%s slice %.3f: n %d err (%.4f %.4f %.4f) sigma (%.4f %.4f %.4f) model %.4f\n",
                name.c_str(), t_begin, n, err.x(), err.y(), err.z(), std::sqrt(cov(0, 0)),
                std::sqrt(cov(1, 1)), std::sqrt(cov(2, 2)), model);
    for (int k = 0; k < 3; ++k) {
      EXPECT_LT(std::abs(err[k]), 5.0 * std::sqrt(cov(k, k)) + leverage[k] * model)
          << name << " axis " << k;
    }
  }
}

TEST(SimLidar, SliceVelocityMatchesTruthVehicular) { checkSliceVelocity("dyna_05", 0.005); }
TEST(SimLidar, SliceVelocityMatchesTruthRotational) { checkSliceVelocity("dyna_04", 0.005); }
TEST(SimLidar, SliceVelocityMatchesTruthStill) { checkSliceVelocity("stat_02", 0.005); }

TEST(SimLidar, FrameLayout) {
  const Recording rec = lidarRecording("dyna_01", 1, 0.5, 6400);
  ASSERT_EQ(rec.frames.size(), 5u);
  for (std::size_t f = 0; f < rec.frames.size(); ++f) {
    const LidarFrame& fr = rec.frames[f];
    EXPECT_DOUBLE_EQ(fr.stamp, rec.config.t0 + static_cast<double>(f) / rec.config.frame_rate);
    EXPECT_GT(fr.points.size(), 5000u);
    EXPECT_EQ(rec.labels[f].size(), fr.points.size());
    for (std::size_t i = 0; i < fr.points.size(); ++i) {
      const DopplerPoint& pt = fr.points[i];
      if (i > 0) {
        EXPECT_GE(pt.time_offset, fr.points[i - 1].time_offset);
      }
      EXPECT_GE(pt.time_offset, 0.0f);
      EXPECT_LT(pt.time_offset, 0.1f);
      EXPECT_LT(pt.line, 64);
      const double r = pt.p_l.cast<double>().norm();
      EXPECT_GT(r, 0.4);
      EXPECT_LT(r, 150.2);
      // Inside the 120 x 30 deg field of view.
      EXPECT_LT(std::abs(std::atan2(pt.p_l.y(), pt.p_l.x())), 60.01 * M_PI / 180.0);
      EXPECT_LT(std::abs(std::asin(pt.p_l.z() / r)), 15.01 * M_PI / 180.0);
      EXPECT_GE(pt.intensity, 0.0f);
      EXPECT_LE(pt.intensity, 1.0f);
    }
  }
}

}  // namespace
}  // namespace freeinit::sim
