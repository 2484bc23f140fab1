// The paper's pipeline (Zhao et al., Sec. III): the Doppler-inertial velocimeter over the window,
// pose integration and mapping at every update, then the accelerometer bias and gravity solve.
//
// Processing is incremental: every processBuffered() processes, in time order, all gyro samples and
// points that the data received so far allow (a point needs the IMU sample after it; a gyro sample
// needs the LiDAR stream to have passed it). A seed pass covers the first [paper_passes]
// seed_duration seconds of the window; its gravity solve starts the accelerometer-aided last pass,
// which catches up on the buffered data and then follows the stream. When the last IMU sample of
// the window has been processed the last solve makes the result final.
#include <freeinit/rotation.h>

#include <cmath>
#include <optional>
#include <sstream>
#include <string>

#include "paper/gravity_estimator.h"
#include "paper/pose_integrator.h"
#include "paper/velocimeter.h"
#include "paper/velocimeter_inputs.h"
#include "paper/velocity_bootstrap.h"
#include "pipeline.h"

namespace freeinit::detail {
namespace {

class PaperPipeline final : public Pipeline {
 public:
  enum class Phase { WaitStart, Running, Done };

  const FreeInitConfig& cfg;
  const MeasurementSequencer& seq;
  const std::vector<ImuSample>& imu;
  InitResult* res = nullptr;
  Phase phase = Phase::WaitStart;

  // Window and cursors.
  double t_ref = 0;               ///< UNIX time of the window start; internal times are relative
  std::size_t k_first = 0;        ///< first IMU sample of the window
  std::size_t k_window_last = 0;  ///< last IMU sample of the window (once known)
  std::size_t k_pass_last = 0;    ///< last IMU sample of the current pass (once closed)
  double pass_duration = 0;       ///< [s] length of the current pass (window rule, config.h)
  bool pass_closed = false;       ///< the last IMU sample of the current pass is processed
  std::size_t k_next = 0;         ///< next IMU sample to process
  MeasurementSequencer::Cursor next;  ///< next point to process
  int point_stride = 1;               ///< the configured stride, or the automatic one
  std::size_t stride_counter = 0;     ///< usable points since the last used one (mod the stride)

  std::optional<Velocimeter> velocimeter;
  PoseIntegrator integrator;
  std::vector<KinematicSample> kinematics;

  // Passes: the paper's, then accelerometer-aided refinements (see PaperPassesParams).
  int pass = 0;
  Vec3 b_g_start = Vec3::Zero();  ///< gyro bias the velocimeter starts from in this pass
  VelocityFit boot_fit;
  bool boot_static = false;
  GravityEstimate gravity;  ///< of the last finished pass

  // Zero-velocity mode.
  bool stationary = false;
  double last_check = 0;
  static constexpr std::size_t kMotionCheckStride = 8;
  std::size_t motion_check_counter = 0;
  std::vector<Vec3> static_dirs;  ///< points since the last motion check
  std::vector<double> static_dopplers;

  PaperPipeline(const FreeInitConfig& c, const MeasurementSequencer& s)
      : cfg(c), seq(s), imu(s.imu()) {}

  /// Time of the point at a normalized cursor, from the window start (t_ref) [s].
  double pointTime(const MeasurementSequencer::Cursor& c) const {
    return (seq.frames()[c.f].stamp - t_ref) + seq.point(c).time_offset;
  }

  void fail(InitStatus s, const std::string& msg) {
    failResult(*res, s, msg);
    phase = Phase::Done;
  }

  bool processBuffered(InitResult& r) override {
    res = &r;
    if (phase == Phase::Done) return true;
    const double t0 = wallSeconds(), solver0 = res->diag.time_solver;
    if (phase == Phase::WaitStart) tryStart();
    if (phase == Phase::Running) run();
    res->diag.time_velocimeter += wallSeconds() - t0 - (res->diag.time_solver - solver0);
    if (phase == Phase::Running && seq.finished()) {
      std::ostringstream window;
      window << cfg.window.duration;
      fail(InitStatus::NotEnoughData, "the recording ends before the initialization window (" +
                                          window.str() + " s) is covered");
    }
    if (phase == Phase::WaitStart && seq.finished())
      fail(InitStatus::NotEnoughData, "no IMU sample overlaps the LiDAR data");
    return phase == Phase::Done;
  }

  void tryStart() {
    if (cfg.doppler.doppler_ego_compensated) {
      fail(InitStatus::NoDoppler,
           "the Doppler values are ego-compensated: they carry no ego velocity; Free-Init needs "
           "the raw (range-rate) Doppler");
      return;
    }
    // Window start: the first IMU sample at or after the first LiDAR point.
    MeasurementSequencer::Cursor c;
    if (!seq.normalize(c) || imu.empty()) return;
    const double tp0 = seq.time(c);
    std::size_t k = 0;
    while (k < imu.size() && imu[k].t < tp0) ++k;
    if (k + 1 >= imu.size()) return;  // need the sample and the next one (gyro slope)
    t_ref = imu[k].t;
    // Bootstrap points: the first ones at or after the window start.
    std::vector<Vec3> dirs;
    std::vector<double> dopplers;
    const DopplerParams& dp = cfg.doppler;
    const int boot_points = cfg.paper_bootstrap.points;
    dirs.reserve(boot_points);
    dopplers.reserve(boot_points);
    for (; seq.normalize(c) && static_cast<int>(dirs.size()) < boot_points; ++c.p) {
      const DopplerPoint& pt = seq.point(c);
      if (pointTime(c) < 0 || !usablePoint(pt, dp)) continue;
      const double r = pt.p_l.norm();
      dirs.push_back(pt.p_l.cast<double>() / r);
      dopplers.push_back(pt.doppler);
    }
    if (static_cast<int>(dirs.size()) < boot_points && !seq.finished()) return;
    if (dirs.size() < 10) {
      fail(InitStatus::NoDoppler, "fewer than 10 usable LiDAR returns in the window");
      return;
    }
    const VelocityFit fit =
        fitLidarVelocity(dirs, dopplers, velocityFitParams(cfg), dp.doppler_sigma);
    if (!fit.ok) {
      fail(InitStatus::DegenerateGeometry, "bootstrap: " + fit.message);
      return;
    }
    k_first = k;
    point_stride =
        dp.point_stride > 0 ? dp.point_stride : automaticPointStride(seq, dp.max_point_rate);
    boot_fit = fit;
    const ImuParams& ip = cfg.imu;
    b_g_start = ip.gyro_bias_prior;
    boot_static = cfg.start.detect_rest && fit.v_l.norm() < cfg.start.rest_speed &&
                  (imu[k_first].gyro - ip.gyro_bias_prior).norm() <
                      cfg.paper_rest.max_gyro_dev + 3.0 * ip.gyro_bias_sigma0;
    startPass();
    phase = Phase::Running;
  }

  /// (Re)starts the velocimeter at the window start; all window data are buffered for pass > 0.
  void startPass() {
    k_next = k_first + 1;
    const double seed = cfg.paper_passes.seed_duration;
    pass_duration =
        finalPass() || seed <= 0 ? cfg.window.duration : std::min(seed, cfg.window.duration);
    pass_closed = false;
    next = {};
    stride_counter = 0;
    kinematics.clear();
    res->static_map.clear();
    res->rejected.clear();
    res->velocities.clear();
    res->trajectory.clear();
    auto& d = res->diag;
    d.points_seen = d.points_used = d.points_skipped = d.points_rejected = d.gyro_updates = 0;
    VelocimeterParams vp = velocimeterParams(cfg);
    vp.gyro_bias_prior = b_g_start;
    velocimeter.emplace(vp, cfg.extrinsics);
    // The bootstrap points are processed again by the filter: its covariance is widened so that
    // it acts as a starting point and a gate, not as information counted twice.
    velocimeter->start(0.0, boot_fit.v_l, boot_fit.cov * 100.0, imu[k_first].gyro);
    velocimeter->setOmegaSlope((imu[k_first + 1].gyro - imu[k_first].gyro) /
                               (imu[k_first + 1].t - imu[k_first].t));
    integrator.reset(0.0, velocimeter->omega_b(), velocimeter->v_b());
    stationary = boot_static;
    d.static_start = boot_static;
    d.static_duration = 0;
    last_check = 0;
    static_dirs.clear();
    static_dopplers.clear();
    motion_check_counter = 0;
    if (pass > 0) setAcceleration(k_first);
    recordSample(k_first);
  }

  /// Aided passes: the body acceleration a_b = f - b_a + R_w0b^T g_w0 at sample k and its slope to
  /// sample k + 1 (gravity in b turns as dg_b/dt = -omega x g_b).
  void setAcceleration(std::size_t k) {
    setAidedAcceleration(*velocimeter, imu, k, gravity.b_a,
                         integrator.R_wb().transpose() * gravity.g_w);
  }

  void run() {
    while (true) {
      const bool have_point = seq.normalize(next);
      const double tp = have_point ? pointTime(next) : 0.0;
      if (!pass_closed) {
        if (k_next >= imu.size()) return;  // wait for IMU
        const WindowSample w =
            windowSample(imu[k_first].t, imu[k_next - 1].t, imu[k_next].t, pass_duration);
        if (w == WindowSample::Outside) {  // after a gap: the pass ended with the sample before
          closePass(k_next - 1);
          continue;
        }
        const double tg = imu[k_next].t - t_ref;
        if (have_point && tp <= tg) {
          processPoint(tp);
          continue;
        }
        // All points before tg are processed if the LiDAR stream has passed tg.
        if (!have_point && !seq.lidarPassed(imu[k_next].t)) return;
        const bool last = w == WindowSample::Last;
        if (!last && k_next + 1 >= imu.size() && !seq.finished()) return;  // need the slope
        processGyro(k_next);
        if (last) closePass(k_next);
        ++k_next;
        continue;
      }
      // The last gyro sample of the pass is processed: later points belong to no window.
      if (!endOfPass()) return;
    }
  }

  void closePass(std::size_t k_last) {
    pass_closed = true;
    k_pass_last = k_last;
    if (finalPass()) k_window_last = k_last;
  }

  /// Solves b_a and gravity; starts the next pass and returns true if there is one.
  bool endOfPass() {
    const double t0 = wallSeconds();
    GravityParams gp = gravityParams(cfg);
    gp.compute_covariance = finalPass();  // earlier passes only need the estimate
    // Each solve starts from the previous pass's estimate (same window start, same frame w0).
    const GravityEstimate previous = gravity;
    gravity =
        GravityEstimator(gp).estimate(kinematics, cfg.extrinsics, velocimeter->covBg(), &previous);
    res->diag.time_solver += wallSeconds() - t0;
    if (!gravity.ok && !finalPass()) {
      // The data of the window are not all there yet: nothing beyond the seed to report.
      fail(InitStatus::SolverFailed, "accelerometer bias / gravity of the seed pass (first " +
                                         std::to_string(k_pass_last - k_first + 1) +
                                         " IMU samples): " + gravity.message);
      return false;
    }
    if (pass < cfg.paper_passes.refinement_passes) {
      ++pass;
      // The next pass integrates with the corrected gyro bias (same prior width: the window's
      // data must not be counted twice).
      b_g_start = velocimeter->b_g() + gravity.delta_b_g;
      startPass();
      return true;
    }
    finalize();
    return false;
  }

  void processPoint(double t) {
    const DopplerPoint& pt = seq.point(next);
    ++next.p;
    auto& diag = res->diag;
    if (t < 0) return;  // before the window
    ++diag.points_seen;
    // One point in the stride (a counter, not a modulo: this runs for every point); the others
    // cost nothing more.
    const bool use = stride_counter == 0;
    const int stride = point_stride * (finalPass() ? 1 : cfg.paper_passes.seed_pass_stride);
    if (++stride_counter == static_cast<std::size_t>(stride)) stride_counter = 0;
    const DopplerParams& dp = cfg.doppler;
    if (!use) {
      ++diag.points_skipped;
      return;
    }
    if (!usablePoint(pt, dp)) {
      ++diag.points_skipped;
      return;
    }
    const double r = pt.p_l.norm();
    velocimeter->propagate(t);
    bool accepted;
    double residual;
    if (stationary) {
      // Zero-velocity mode: points only feed the motion check and the map.
      const Vec3 d = pt.p_l.cast<double>() / r;
      residual = pt.doppler + d.dot(velocimeter->v_l());
      accepted = std::abs(residual) < dp.gate_min;
      // One point in kMotionCheckStride is plenty for a 3-D velocity every check period.
      if (++motion_check_counter % kMotionCheckStride == 0) {
        static_dirs.push_back(d);
        static_dopplers.push_back(pt.doppler);
      }
    } else {
      const auto out = velocimeter->updateDoppler(pt.p_l, pt.doppler);
      accepted = out.accepted;
      residual = out.residual;
    }
    integrator.integrate(t, velocimeter->omega_b(), velocimeter->v_b());
    if (accepted)
      ++diag.points_used;
    else
      ++diag.points_rejected;
    if (!finalPass()) return;  // earlier passes are refined: only the last one maps
    MapPoint m;
    const Vec3 p_b = cfg.extrinsics.R_bl * pt.p_l.cast<double>() + cfg.extrinsics.p_bl;
    m.p_w = (integrator.q_wb() * p_b + integrator.p_w()).cast<float>();
    m.intensity = pt.intensity;
    m.residual = static_cast<float>(residual);
    m.doppler = pt.doppler;
    m.time = static_cast<float>(t);  // from t_ref; from the state's time once that is known
    (accepted ? res->static_map : res->rejected).push_back(m);
  }

  /// The pass whose map and trajectory are the result (unless its gravity solve fails).
  bool finalPass() const { return pass >= cfg.paper_passes.refinement_passes; }

  void processGyro(std::size_t k) {
    const double t = imu[k].t - t_ref;
    velocimeter->propagate(t);
    if (stationary) {
      velocimeter->updateZeroVelocity(cfg.paper_rest.zupt_sigma);
      checkMotion(k, t);
    }
    updateGyroAt(*velocimeter, imu, k);
    ++res->diag.gyro_updates;
    integrator.integrate(t, velocimeter->omega_b(), velocimeter->v_b());
    if (pass > 0) setAcceleration(k);
    recordSample(k);
  }

  /// Leaves zero-velocity mode as soon as the Doppler or the gyro shows motion.
  void checkMotion(std::size_t k, double t) {
    const PaperRestParams& rp = cfg.paper_rest;
    // The gyro deviates from the bias estimate by more than its own uncertainty allows.
    const double sigma_bg = std::sqrt(velocimeter->covBg().diagonal().maxCoeff());
    bool moving = (imu[k].gyro - velocimeter->b_g()).norm() > rp.max_gyro_dev + 3.0 * sigma_bg;
    Vec3 v_ls = Vec3::Zero();
    if (t - last_check >= rp.check_period) {
      // Robust (IRLS) velocity of the points since the last check: moving objects in view must
      // not look like ego motion.
      const VelocityFit fit = fitLidarVelocity(static_dirs, static_dopplers, velocityFitParams(cfg),
                                               cfg.doppler.doppler_sigma);
      // Moving: faster than [start] rest_speed, and significantly non-zero (5 sigma) given how
      // well the few points of a sparse scene constrain the velocity.
      if (fit.ok && fit.v_l.norm() > cfg.start.rest_speed &&
          fit.v_l.dot(fit.cov.ldlt().solve(fit.v_l)) > 25.0) {
        v_ls = fit.v_l;
        moving = true;
      }
      static_dirs.clear();
      static_dopplers.clear();
      last_check = t;
    }
    if (!moving) return;
    stationary = false;
    res->diag.static_duration = t;
    velocimeter->releaseZeroVelocity(std::max(0.2, 2.0 * v_ls.norm()), 0.5);
  }

  void recordSample(std::size_t k) {
    KinematicSample s;
    s.t = imu[k].t - t_ref;
    s.R_wb = integrator.R_wb();
    s.v_b = velocimeter->v_b();
    s.cov_v_b = velocimeter->covVb();
    s.v_l = velocimeter->v_l();
    s.cov_v_l = velocimeter->covVl();
    s.omega_b = velocimeter->omega_b();
    s.accel = imu[k].accel;
    kinematics.push_back(s);
    VelocitySample v;
    v.t = imu[k].t;
    v.v_l = s.v_l;
    v.v_b = s.v_b;
    v.omega_b = s.omega_b;
    v.b_g = velocimeter->b_g();
    v.sigma_v_b = s.cov_v_b.diagonal().cwiseSqrt();
    v.stationary = stationary;
    res->velocities.push_back(v);
    PoseSample p;
    p.t = imu[k].t;
    p.q_wb = integrator.q_wb().normalized();
    p.p_w = integrator.p_w();
    res->trajectory.push_back(p);
  }

  void finalize();
};

void PaperPipeline::finalize() {
  phase = Phase::Done;
  auto& diag = res->diag;
  if (stationary) diag.static_duration = imu[k_window_last].t - t_ref;
  const double T = imu[k_window_last].t - t_ref;
  diag.update_rate_hz = T > 0 ? static_cast<double>(diag.points_used + diag.gyro_updates) / T : 0;
  if (diag.points_used < 10 && !diag.static_start) {
    fail(InitStatus::NoDoppler, "no Doppler return passed the gate in the window");
    return;
  }
  const GravityEstimate& ge = gravity;
  diag.solver_report = ge.message;
  if (!ge.ok) {
    fail(InitStatus::SolverFailed, "accelerometer bias / gravity: " + ge.message);
    return;
  }

  // Gyro-bias correction of the attitude (left, world-frame perturbation, see GravityEstimate):
  // R_w0b,true(t) = Exp(-M(t) db) R_w0b(t), M(t) = int_0^t R_w0b dt.
  std::vector<Mat3> M(kinematics.size(), Mat3::Zero());
  for (std::size_t k = 1; k < kinematics.size(); ++k)
    M[k] = M[k - 1] + 0.5 * (kinematics[k].t - kinematics[k - 1].t) *
                          (kinematics[k - 1].R_wb + kinematics[k].R_wb);
  const Vec3& db = ge.delta_b_g;
  for (std::size_t k = 0; k < res->trajectory.size() && k < M.size(); ++k) {
    auto& q = res->trajectory[k].q_wb;
    q = (Quat(Exp(Vec3(-M[k] * db))) * q).normalized();
  }
  const Mat3 M_end = M.back();
  const Mat3 R_w0b = Exp(Vec3(-M_end * db)) * integrator.R_wb();

  // Gravity-aligned world with the yaw of the first body frame (w0).
  const Mat3 R_align = alignToGravity(ge.g_w);
  const Mat3 R_wb = R_align * R_w0b;
  InitialState& s = res->state;
  s.status = InitStatus::Ok;
  s.message.clear();
  s.timestamp = imu[k_window_last].t;
  s.q_wb = Quat(R_wb).normalized();
  s.p_w = R_align * integrator.p_w();
  const Vec3 v_b = velocimeter->v_b();
  s.v_w = R_wb * v_b;
  s.b_g = velocimeter->b_g() + db;
  s.b_a = ge.b_a;
  s.g_w = Vec3(0, 0, -kGravity);

  // Covariance, order [dtheta p v b_g b_a g], dtheta a right perturbation of R_wb.
  // x = [dg_w0, db_a, db_g] has the solver's covariance; where the solver did not estimate the
  // gyro bias its block is the velocimeter's (uncorrelated).
  Eigen::Matrix<double, 9, 9> C = ge.cov_full;
  if (C.block<3, 3>(6, 6).isZero()) {
    C.block<3, 3>(6, 6) = velocimeter->covBg();
  }
  // Tilt: g_b = R_w0b^T g_w0 with R_w0b,true = Exp(-M_end db) R_w0b, so
  //   dg_b = R_w0b^T (dg_w0 - [g_w0]x M_end db),  and g_b,true = g_b + [g_b]x dtheta gives the
  // tangent part dtheta = -[g_b]x dg_b / |g|^2. Yaw (about gravity) from the gyro bias only:
  //   the right perturbation of Exp(-M_end db) R_w0b is -R_w0b^T M_end db.
  const Vec3 g_b = R_w0b.transpose() * ge.g_w;
  const Vec3 up_b = -g_b.normalized();
  const double g2 = kGravity * kGravity;
  Eigen::Matrix<double, 3, 9> A_th = Eigen::Matrix<double, 3, 9>::Zero();
  A_th.block<3, 3>(0, 0) = -skew(g_b) * R_w0b.transpose() / g2;
  A_th.block<3, 3>(0, 6) = skew(g_b) * R_w0b.transpose() * skew(ge.g_w) * M_end / g2 -
                           up_b * up_b.transpose() * R_w0b.transpose() * M_end;
  const double dt_imu = T / static_cast<double>(std::max<std::size_t>(1, k_window_last - k_first));
  const double var_gyro_walk = cfg.imu.gyro_sigma * cfg.imu.gyro_sigma * dt_imu * T;
  // P = G S G^T over independent error sources, so it is a covariance by construction:
  //   [dg_w0, db_a, db_g] (solver, 9), dv_b (velocimeter, 3), gyro white noise integrated into
  //   the attitude (3), position and gravity floors (3 + 3).
  // dtheta = A_th [dg db_a db_g] + n_walk;  dv_w = R_wb dv_b + J_v_th dtheta (J_v_th = -R [v_b]x);
  // dp = T R_wb dv_b + n_p (velocity errors over the window taken as fully correlated: an upper
  // bound this short); gravity is fixed by the choice of world frame (its uncertainty lives in the
  // attitude block), given a 1e-6 floor.
  constexpr int kSrc = 21;
  Eigen::Matrix<double, kSrc, kSrc> S = Eigen::Matrix<double, kSrc, kSrc>::Zero();
  S.block<9, 9>(0, 0) = C;
  S.block<3, 3>(9, 9) = velocimeter->covVb();
  S.block<3, 3>(12, 12) = Mat3::Identity() * var_gyro_walk;
  S.block<6, 6>(15, 15) = Eigen::Matrix<double, 6, 6>::Identity() * 1e-6;
  Eigen::Matrix<double, 18, kSrc> G = Eigen::Matrix<double, 18, kSrc>::Zero();
  G.block<3, 9>(kTheta, 0) = A_th;
  G.block<3, 3>(kTheta, 12) = Mat3::Identity();
  G.block<3, 3>(kPos, 9) = R_wb * T;
  G.block<3, 3>(kPos, 15) = Mat3::Identity();
  const Mat3 J_v_th = -R_wb * skew(v_b);
  G.block<3, 3>(kVel, 9) = R_wb;
  G.block<3, kSrc>(kVel, 0) += J_v_th * G.block<3, kSrc>(kTheta, 0);
  G.block<3, 3>(kBg, 6) = Mat3::Identity();
  G.block<3, 3>(kBa, 3) = Mat3::Identity();
  G.block<3, 3>(kGrav, 18) = Mat3::Identity();
  const Cov18 P = G * S * G.transpose();
  s.cov = 0.5 * (P + P.transpose());

  // Express everything recorded in the first body frame in the aligned world.
  const Quat q_align(R_align);
  const float t_state = static_cast<float>(s.timestamp - t_ref);
  for (auto* map : {&res->static_map, &res->rejected}) {
    for (auto& m : *map) {
      m.p_w = (R_align * m.p_w.cast<double>()).cast<float>();
      m.time -= t_state;
    }
  }
  for (auto& p : res->trajectory) {
    p.q_wb = (q_align * p.q_wb).normalized();
    p.p_w = R_align * p.p_w;
  }
}

}  // namespace

std::unique_ptr<Pipeline> makePaperPipeline(const FreeInitConfig& config,
                                            const MeasurementSequencer& sequencer) {
  return std::make_unique<PaperPipeline>(config, sequencer);
}

}  // namespace freeinit::detail
