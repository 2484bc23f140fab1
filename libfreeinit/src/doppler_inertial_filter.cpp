#include <freeinit/doppler_inertial_filter.h>
#include <freeinit/rotation.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace freeinit {
namespace {

const Vec3 kGravityW(0, 0, -kGravity);
/// Step of the central differences of the numerical Jacobians (state units: rad, m, m/s, rad/s,
/// m/s^2; the functions are smooth and O(1-100) in these units).
constexpr double kJacobianStep = 1e-6;

/// Rotation over a signed interval tau from rate w0 (at its start) to w1 (at its end), the rate
/// linear in between: midpoint rotation vector plus the coning correction, third order in tau.
Vec3 rotationIncrement(const Vec3& w0, const Vec3& w1, double tau) {
  return 0.5 * (w0 + w1) * tau + w0.cross(w1) * (tau * tau / 12.0);
}

/// Right Jacobian of SO(3): Exp(phi + dphi) = Exp(phi) Exp(J_r(phi) dphi) to first order.
Mat3 rightJacobian(const Vec3& phi) {
  const double t2 = phi.squaredNorm();
  const Mat3 K = skew(phi);
  if (t2 < 1e-8) return Mat3::Identity() - 0.5 * K + (1.0 / 6.0) * K * K;
  const double t = std::sqrt(t2);
  return Mat3::Identity() - (1.0 - std::cos(t)) / t2 * K + (t - std::sin(t)) / (t2 * t) * K * K;
}

/// d phi / d b_g of rotationIncrement (both rates are gyro - b_g).
Mat3 incrementBiasJacobian(const Vec3& w0, const Vec3& w1, double tau) {
  return -tau * Mat3::Identity() - (tau * tau / 12.0) * skew(Vec3(w0 - w1));
}

}  // namespace

DopplerInertialFilter::DopplerInertialFilter(const DopplerInertialFilterParams& params,
                                             const Extrinsics& extrinsics)
    : params_(params), R_bl_(extrinsics.R_bl), p_bl_(extrinsics.p_bl) {
  gate_min2_ = params.gate_min * params.gate_min;
  gate_k2_ = params.gate_sigma * params.gate_sigma;
  r_doppler_ = params.doppler_sigma * params.doppler_sigma;
}

FilterState DopplerInertialFilter::boxplus(const FilterState& x, const Vec15& dx) {
  FilterState y = x;
  y.R_wb = x.R_wb * Exp(Vec3(dx.segment<3>(0)));
  y.p_w += dx.segment<3>(3);
  y.v_w += dx.segment<3>(6);
  y.b_g += dx.segment<3>(9);
  y.b_a += dx.segment<3>(12);
  return y;
}

DopplerInertialFilter::Vec15 DopplerInertialFilter::boxminus(const FilterState& a,
                                                             const FilterState& b) {
  Vec15 d;
  d.segment<3>(0) = Log(b.R_wb.transpose() * a.R_wb);
  d.segment<3>(3) = a.p_w - b.p_w;
  d.segment<3>(6) = a.v_w - b.v_w;
  d.segment<3>(9) = a.b_g - b.b_g;
  d.segment<3>(12) = a.b_a - b.b_a;
  return d;
}

FilterState DopplerInertialFilter::propagate(const FilterState& x, const ImuSample& a,
                                             const ImuSample& b) {
  const double dt = b.t - a.t;
  FilterState y = x;
  y.t = b.t;
  const Vec3 w0 = a.gyro - x.b_g, w1 = b.gyro - x.b_g;
  y.R_wb = x.R_wb * Exp(rotationIncrement(w0, w1, dt));
  const Vec3 acc0 = x.R_wb * (a.accel - x.b_a) + kGravityW;
  const Vec3 acc1 = y.R_wb * (b.accel - x.b_a) + kGravityW;
  y.v_w = x.v_w + 0.5 * dt * (acc0 + acc1);
  y.p_w = x.p_w + x.v_w * dt + (dt * dt / 6.0) * (2.0 * acc0 + acc1);
  return y;
}

DopplerInertialFilter::Mat15 DopplerInertialFilter::transitionJacobian(const FilterState& x,
                                                                      const ImuSample& a,
                                                                      const ImuSample& b) {
  // Error propagation of propagate() (right attitude perturbation, world-frame p and v):
  //   dtheta' = Exp(phi)^T dtheta + J_r(phi) dphi/db_g db_g
  //   dacc_i  = -R_i [f_i - b_a]x dtheta_i - R_i db_a       (i = 0 at a, 1 at b)
  //   dv'     = dv + dt/2 (dacc0 + dacc1),  dp' = dp + dt dv + dt^2/6 (2 dacc0 + dacc1)
  const double dt = b.t - a.t;
  const Vec3 w0 = a.gyro - x.b_g, w1 = b.gyro - x.b_g;
  const Vec3 phi = rotationIncrement(w0, w1, dt);
  const Mat3 E = Exp(phi);
  const Mat3 R1 = x.R_wb * E;
  const Vec3 f0 = a.accel - x.b_a, f1 = b.accel - x.b_a;
  Mat15 F = Mat15::Identity();
  // Rows of dtheta'.
  const Mat3 th_th = E.transpose();
  const Mat3 th_bg = rightJacobian(phi) * incrementBiasJacobian(w0, w1, dt);
  F.block<3, 3>(0, 0) = th_th;
  F.block<3, 3>(0, 9) = th_bg;
  // dacc0 and dacc1 as rows over (dtheta, db_g, db_a).
  const Mat3 a0_th = -x.R_wb * skew(f0), a0_ba = -x.R_wb;
  const Mat3 a1_th = -R1 * skew(f1) * th_th, a1_bg = -R1 * skew(f1) * th_bg, a1_ba = -R1;
  F.block<3, 3>(6, 0) = 0.5 * dt * (a0_th + a1_th);
  F.block<3, 3>(6, 9) = 0.5 * dt * a1_bg;
  F.block<3, 3>(6, 12) = 0.5 * dt * (a0_ba + a1_ba);
  const double c = dt * dt / 6.0;
  F.block<3, 3>(3, 6) = dt * Mat3::Identity();
  F.block<3, 3>(3, 0) = c * (2.0 * a0_th + a1_th);
  F.block<3, 3>(3, 9) = c * a1_bg;
  F.block<3, 3>(3, 12) = c * (2.0 * a0_ba + a1_ba);
  return F;
}

DopplerInertialFilter::Mat15 DopplerInertialFilter::numericalTransitionJacobian(
    const FilterState& x, const ImuSample& a, const ImuSample& b) {
  const FilterState y = propagate(x, a, b);
  Mat15 F;
  for (int i = 0; i < 15; ++i) {
    Vec15 e = Vec15::Zero();
    e(i) = kJacobianStep;
    const Vec15 plus = boxminus(propagate(boxplus(x, e), a, b), y);
    const Vec15 minus = boxminus(propagate(boxplus(x, -e), a, b), y);
    F.col(i) = (plus - minus) / (2.0 * kJacobianStep);
  }
  return F;
}

Vec3 DopplerInertialFilter::lidarVelocity(const FilterState& x, const ImuSample* prev,
                                          const ImuSample& cur, const ImuSample* next, double tau,
                                          Eigen::Matrix<double, 3, 15>* J) const {
  const ImuSample* other = tau > 0 ? next : (tau < 0 ? prev : nullptr);
  double alpha = 0;
  if (other != nullptr && other->t != cur.t) alpha = tau / (other->t - cur.t);
  const Vec3 gyro = other ? Vec3(cur.gyro + alpha * (other->gyro - cur.gyro)) : cur.gyro;
  const Vec3 accel = other ? Vec3(cur.accel + alpha * (other->accel - cur.accel)) : cur.accel;
  const Vec3 w0 = cur.gyro - x.b_g, w1 = gyro - x.b_g;
  const Vec3 phi = rotationIncrement(w0, w1, tau);
  const Mat3 E = Exp(phi);
  const Mat3 R = x.R_wb * E;
  const Vec3 f0 = cur.accel - x.b_a, f1 = accel - x.b_a;
  const Vec3 v_w = x.v_w + 0.5 * tau * (x.R_wb * f0 + R * f1) + kGravityW * tau;
  const Vec3 v_b = R.transpose() * v_w;
  if (J != nullptr) {
    // dtheta_tau = E^T dtheta + J_r(phi) dphi/db_g db_g
    // dv_w = dv + tau/2 (-R_k [f0]x dtheta - R_k db_a - R [f1]x dtheta_tau - R db_a)
    // dv_b = R^T dv_w + [v_b]x dtheta_tau;  dv_l = R_bl^T (dv_b + [p_bl]x db_g)
    const Mat3 th_th = E.transpose();
    const Mat3 th_bg = rightJacobian(phi) * incrementBiasJacobian(w0, w1, tau);
    const Mat3 Rt = R.transpose();
    const Mat3 vw_th = -0.5 * tau * (x.R_wb * skew(f0) + R * skew(f1) * th_th);
    const Mat3 vw_bg = -0.5 * tau * R * skew(f1) * th_bg;
    const Mat3 vw_ba = -0.5 * tau * (x.R_wb + R);
    const Mat3 S = skew(v_b);
    const Mat3 Rlb = R_bl_.transpose();
    J->setZero();
    J->block<3, 3>(0, 0) = Rlb * (Rt * vw_th + S * th_th);
    J->block<3, 3>(0, 6) = Rlb * Rt;
    J->block<3, 3>(0, 9) = Rlb * (Rt * vw_bg + S * th_bg + skew(p_bl_));
    J->block<3, 3>(0, 12) = Rlb * Rt * vw_ba;
  }
  return R_bl_.transpose() * (v_b + w1.cross(p_bl_));
}

DopplerInertialFilter::Vec9 DopplerInertialFilter::velocityPolynomial(const Node& n,
                                                                       const FilterState& x,
                                                                       Mat9x15* G) const {
  // Values at the three fit instants, then the quadratic through them: Q_m = sum_i Vinv(m, i) v_i.
  const Mat3& Vinv = n.V_inv;
  Vec9 Q = Vec9::Zero();
  if (G != nullptr) G->setZero();
  Eigen::Matrix<double, 3, 15> J;
  for (int i = 0; i < 3; ++i) {
    const Vec3 v = lidarVelocity(x, n.has_prev ? &n.imu_prev : nullptr, n.imu,
                                 n.has_next ? &n.imu_next : nullptr, n.s_fit[i] * n.h,
                                 G != nullptr ? &J : nullptr);
    for (int m = 0; m < 3; ++m) {
      Q.segment<3>(3 * m) += Vinv(m, i) * v;
      if (G != nullptr) G->middleRows<3>(3 * m) += Vinv(m, i) * J;
    }
  }
  return Q;
}

DopplerInertialFilter::Mat15 DopplerInertialFilter::processNoise(double dt) const {
  Mat15 Q = Mat15::Zero();
  const double qg = params_.gyro_sigma * params_.gyro_sigma * dt * dt;
  const double qa = params_.accel_sigma * params_.accel_sigma * dt * dt;
  Q.block<3, 3>(0, 0).diagonal().setConstant(qg);
  // Velocity noise qa; position integrates it (dt/2 per step, fully correlated within the step).
  Q.block<3, 3>(6, 6).diagonal().setConstant(qa);
  Q.block<3, 3>(3, 3).diagonal().setConstant(qa * dt * dt / 4.0);
  Q.block<3, 3>(3, 6).diagonal().setConstant(qa * dt / 2.0);
  Q.block<3, 3>(6, 3).diagonal().setConstant(qa * dt / 2.0);
  Q.block<3, 3>(9, 9).diagonal().setConstant(params_.gyro_bias_random_walk *
                                             params_.gyro_bias_random_walk * dt);
  Q.block<3, 3>(12, 12).diagonal().setConstant(params_.accel_bias_random_walk *
                                               params_.accel_bias_random_walk * dt);
  return Q;
}

void DopplerInertialFilter::start(const ImuSample& s0, const FilterState& x0, const Mat15& P0,
                                  const Mat15* P_gate) {
  P_gate0_ = P_gate != nullptr ? *P_gate : P0;
  nodes_.clear();
  x0_prior_ = x0;
  x0_prior_.t = s0.t;
  P0_ = 0.5 * (P0 + P0.transpose());
  Node n;
  n.imu = s0;
  n.x_pred = x0_prior_;
  n.x = n.xs = x0_prior_;
  n.P = P0_;
  nodes_.push_back(n);
}

void DopplerInertialFilter::predict(const ImuSample& s) {
  if (nodes_.empty()) throw std::logic_error("DopplerInertialFilter::predict before start");
  const Node& cur = nodes_.back();
  Node n;
  n.imu = s;
  n.imu_prev = cur.imu;
  n.has_prev = true;
  const Mat15 F = transitionJacobian(cur.x, cur.imu, s);
  n.x_pred = propagate(cur.x, cur.imu, s);
  n.P = F * cur.P * F.transpose() + processNoise(s.t - cur.imu.t);
  n.P = 0.5 * (n.P + n.P.transpose()).eval();
  n.x = n.xs = n.x_pred;
  nodes_.push_back(n);
}

void DopplerInertialFilter::beginNode(const ImuSample* next) {
  Node& n = nodes_.back();
  n.has_next = next != nullptr;
  if (next) n.imu_next = *next;
  before_ = n.has_prev ? 0.5 * (n.imu.t - n.imu_prev.t) : 0.0;
  after_ = n.has_next ? 0.5 * (n.imu_next.t - n.imu.t) : 0.0;
  n.h = std::max({before_, after_, 1e-6});
  if (before_ > 0 && after_ > 0)
    n.s_fit = {-before_ / n.h, 0.0, after_ / n.h};
  else if (after_ > 0)
    n.s_fit = {0.0, 0.5 * after_ / n.h, after_ / n.h};
  else
    n.s_fit = {-before_ / n.h, -0.5 * before_ / n.h, 0.0};
  if (before_ == 0 && after_ == 0) n.s_fit = {-1.0, 0.0, 1.0};  // a lone node: any three
  Mat3 V;
  for (int i = 0; i < 3; ++i) V.row(i) << 1.0, n.s_fit[i], n.s_fit[i] * n.s_fit[i];
  n.V_inv = V.inverse();
  n.sums = DopplerSums{};
  Mat9x15 G;
  q_open_ = velocityPolynomial(n, n.x_pred, &G);
  const Eigen::Matrix<double, 3, 15> G0 = G.topRows<3>();
  M_open_ = G0 * (nodes_.size() == 1 ? P_gate0_ : n.P) * G0.transpose();
}

DopplerInertialFilter::PointOutcome DopplerInertialFilter::addPoint(double tau,
                                                                    const Eigen::Vector3f& p_l,
                                                                    double doppler) {
  Node& n = nodes_.back();
  PointOutcome out;
  const Vec3 p = p_l.cast<double>();
  const Vec3 d = p.normalized();
  const double s = tau / n.h;
  const Vec3 q = q_open_.segment<3>(0) + s * (q_open_.segment<3>(3) + s * q_open_.segment<3>(6));
  const double r = doppler + d.dot(q);
  out.residual = r;
  const double S = d.dot(M_open_ * d) + r_doppler_;
  const double gate =
      std::sqrt(std::max(gate_min2_, gate_k2_ * S)) + params_.gate_rel * q_open_.head<3>().norm();
  // The point in the node's body frame: the body moved by tau (omega, v_b) since the node.
  const Vec3 p_b = R_bl_ * p + p_bl_;
  const Vec3 omega = n.imu.gyro - n.x_pred.b_g;
  const Vec3 v_b = n.x_pred.R_wb.transpose() * n.x_pred.v_w;
  out.x_b = (p_b + tau * (omega.cross(p_b) + v_b)).cast<float>();
  if (std::abs(r) > gate) return out;
  out.accepted = true;
  DopplerSums& S_ = n.sums;
  const Mat3 dd = d * d.transpose();
  double sm = 1.0;
  for (int m = 0; m < 5; ++m) {
    S_.S[static_cast<std::size_t>(m)] += sm * dd;
    if (m < 3) S_.bz[static_cast<std::size_t>(m)] += (sm * doppler) * d;
    sm *= s;
  }
  S_.c += doppler * doppler;
  ++S_.n;
  return out;
}

void DopplerInertialFilter::buildRows(Node& n) const {
  n.rows.W.resize(0, 9);
  n.rows.y0.resize(0);
  if (n.sums.n == 0) return;
  Eigen::Matrix<double, 9, 9> A;
  Vec9 b;
  for (int m = 0; m < 3; ++m) {
    b.segment<3>(3 * m) = n.sums.bz[static_cast<std::size_t>(m)];
    for (int k = 0; k < 3; ++k)
      A.block<3, 3>(3 * m, 3 * k) = n.sums.S[static_cast<std::size_t>(m + k)];
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> es(A);
  const double max_ev = es.eigenvalues().maxCoeff();
  int rows = 0;
  for (int i = 0; i < 9; ++i)
    if (es.eigenvalues()(i) > 1e-10 * max_ev && es.eigenvalues()(i) > 1e-12) ++rows;
  n.rows.W.resize(rows, 9);
  n.rows.y0.resize(rows);
  const double inv_sigma = 1.0 / params_.doppler_sigma;
  int r = 0;
  for (int i = 0; i < 9; ++i) {
    const double ev = es.eigenvalues()(i);
    if (!(ev > 1e-10 * max_ev && ev > 1e-12)) continue;
    const Vec9 u = es.eigenvectors().col(i);
    n.rows.W.row(r) = std::sqrt(ev) * inv_sigma * u.transpose();
    n.rows.y0(r) = u.dot(b) / std::sqrt(ev) * inv_sigma;
    ++r;
  }
}

DopplerInertialFilter::Vec15 DopplerInertialFilter::dopplerUpdate(const Node& n,
                                                                  const FilterState& x_lin,
                                                                  const Vec15& dx_prior,
                                                                  Mat15& P) const {
  const int rows = static_cast<int>(n.rows.W.rows());
  if (rows == 0) return dx_prior;
  Mat9x15 G;
  const Vec9 Q = velocityPolynomial(n, x_lin, &G);
  using RowsX15 = Eigen::Matrix<double, Eigen::Dynamic, 15, 0, 9, 15>;
  using RowsX1 = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 9, 1>;
  using RowsXRows = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 9, 9>;
  const RowsX15 H = n.rows.W * G;
  const RowsX1 innovation = -(n.rows.W * Q + n.rows.y0) - H * dx_prior;
  RowsXRows S = H * P * H.transpose();
  S.diagonal().array() += 1.0;
  const RowsX15 HP = H * P;
  const Eigen::Matrix<double, 15, Eigen::Dynamic, 0, 15, 9> K = S.ldlt().solve(HP).transpose();
  const Vec15 dx = dx_prior + K * innovation;
  const Mat15 IKH = Mat15::Identity() - K * H;
  P = IKH * P * IKH.transpose() + K * K.transpose();
  P = 0.5 * (P + P.transpose()).eval();
  return dx;
}

void DopplerInertialFilter::update() {
  Node& n = nodes_.back();
  buildRows(n);
  if (n.rows.W.rows() == 0) return;
  const Mat15 P_pred = n.P;
  FilterState x_lin = n.x_pred;
  Mat15 P = P_pred;
  // Iterated update: re-linearize at the updated state while the correction moves it.
  for (int it = 0; it < 3; ++it) {
    P = P_pred;
    const Vec15 dx_prior = boxminus(n.x_pred, x_lin);
    const Vec15 dx = dopplerUpdate(n, x_lin, dx_prior, P);
    x_lin = boxplus(x_lin, dx);
    if (dx.norm() < 1e-9) break;
  }
  n.x = n.xs = x_lin;
  n.P = P;
}

DopplerInertialFilter::Vec15 DopplerInertialFilter::restUpdate(const Node& n,
                                                               const FilterState& x_lin,
                                                               const Vec15& dx, Mat15& P) {
  if (!(n.rest_velocity_sigma > 0) && !(n.rest_rate_sigma > 0)) return dx;
  // Zero velocity: v_b = R^T v_w = 0, dv_b = R^T dv_w + [v_b]x dtheta. Zero rate: the gyro
  // sample measures the bias, gyro - b_g = 0 + n, d(.) = -db_g. Stacked, relative to x_lin + dx.
  Eigen::Matrix<double, 6, 15> H = Eigen::Matrix<double, 6, 15>::Zero();
  Eigen::Matrix<double, 6, 1> y = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 1> r = Eigen::Matrix<double, 6, 1>::Zero();
  const FilterState x = boxplus(x_lin, dx);
  const Vec3 v_b = x.R_wb.transpose() * x.v_w;
  int rows = 0;
  if (n.rest_velocity_sigma > 0) {
    H.block<3, 3>(0, 0) = skew(v_b);
    H.block<3, 3>(0, 6) = x.R_wb.transpose();
    y.head<3>() = -v_b;
    r.head<3>().setConstant(n.rest_velocity_sigma * n.rest_velocity_sigma);
    rows = 3;
  }
  if (n.rest_rate_sigma > 0) {
    H.block<3, 3>(rows, 9) = Mat3::Identity();
    y.segment<3>(rows) = n.imu.gyro - x.b_g;
    r.segment<3>(rows).setConstant(n.rest_rate_sigma * n.rest_rate_sigma);
    rows += 3;
  }
  using RowsX15 = Eigen::Matrix<double, Eigen::Dynamic, 15, 0, 6, 15>;
  using RowsXRows = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;
  const RowsX15 Hr = H.topRows(rows);
  RowsXRows S = Hr * P * Hr.transpose();
  S.diagonal() += r.head(rows);
  const Eigen::Matrix<double, 15, Eigen::Dynamic, 0, 15, 6> K =
      S.ldlt().solve(Hr * P).transpose();
  const Vec15 out = dx + K * y.head(rows);
  // Joseph form: the rest constraints are strong, the plain form loses symmetry and definiteness.
  const Mat15 IKH = Mat15::Identity() - K * Hr;
  P = IKH * P * IKH.transpose() + K * r.head(rows).asDiagonal() * K.transpose();
  P = 0.5 * (P + P.transpose()).eval();
  return out;
}

void DopplerInertialFilter::updateRest(double velocity_sigma, double rate_sigma) {
  Node& n = nodes_.back();
  n.rest_velocity_sigma = velocity_sigma;
  n.rest_rate_sigma = rate_sigma;
  Mat15 P = n.P;
  const Vec15 dx = restUpdate(n, n.x, Vec15::Zero(), P);
  n.x = n.xs = boxplus(n.x, dx);
  n.P = P;
}

int DopplerInertialFilter::smooth() {
  const std::size_t N = nodes_.size();
  if (N == 0) return 0;
  std::vector<Vec15> dx_f(N), dx_p(N);
  std::vector<Mat15> P_f(N), P_p(N), F(N > 0 ? N - 1 : 0);
  int iterations = 0;
  for (int it = 0; it < params_.max_iterations; ++it) {
    ++iterations;
    // Forward: a Kalman filter on the errors around the nominal trajectory xs.
    dx_p[0] = boxminus(x0_prior_, nodes_[0].xs);
    P_p[0] = P0_;
    for (std::size_t k = 0; k < N; ++k) {
      Node& n = nodes_[k];
      Mat15 P = P_p[k];
      dx_f[k] = restUpdate(n, n.xs, dopplerUpdate(n, n.xs, dx_p[k], P), P);
      P_f[k] = P;
      if (k + 1 == N) break;
      const Node& m = nodes_[k + 1];
      F[k] = transitionJacobian(n.xs, n.imu, m.imu);
      dx_p[k + 1] = F[k] * dx_f[k] + boxminus(propagate(n.xs, n.imu, m.imu), m.xs);
      P_p[k + 1] = F[k] * P * F[k].transpose() + processNoise(m.imu.t - n.imu.t);
      P_p[k + 1] = 0.5 * (P_p[k + 1] + P_p[k + 1].transpose()).eval();
    }
    // Backward: Rauch-Tung-Striebel.
    Vec15 dx_s = dx_f[N - 1];
    nodes_[N - 1].P = P_f[N - 1];
    std::vector<Vec15> dxs(N);
    dxs[N - 1] = dx_s;
    for (std::size_t k = N - 1; k-- > 0;) {
      const Eigen::LDLT<Mat15> ldlt(P_p[k + 1]);
      const Mat15 C = ldlt.solve(F[k] * P_f[k]).transpose();  // P_f F^T P_p^-1
      dxs[k] = dx_f[k] + C * (dxs[k + 1] - dx_p[k + 1]);
      nodes_[k].P = P_f[k];
    }
    // Converged when no node moves by more than the tolerance of its block (scaled).
    Vec15 tol;
    tol << Vec3::Constant(1e-5), Vec3::Constant(1e-4), Vec3::Constant(1e-4), Vec3::Constant(1e-6),
        Vec3::Constant(1e-4);
    double largest = 0;
    for (std::size_t k = 0; k < N; ++k) {
      nodes_[k].xs = boxplus(nodes_[k].xs, dxs[k]);
      largest = std::max(largest, dxs[k].cwiseAbs().cwiseQuotient(tol).maxCoeff());
    }
    if (largest < params_.convergence) break;
  }
  return iterations;
}

double DopplerInertialFilter::residualSumOfSquares() const {
  double rss = 0;
  for (const Node& n : nodes_) {
    if (n.sums.n == 0) continue;
    const Vec9 Q = velocityPolynomial(n, n.xs, nullptr);
    double quad = 0, lin = 0;
    for (int m = 0; m < 3; ++m) {
      lin += n.sums.bz[static_cast<std::size_t>(m)].dot(Q.segment<3>(3 * m));
      for (int k = 0; k < 3; ++k)
        quad += Q.segment<3>(3 * m).dot(n.sums.S[static_cast<std::size_t>(m + k)] *
                                        Q.segment<3>(3 * k));
    }
    rss += n.sums.c + 2.0 * lin + quad;
  }
  return std::max(0.0, rss);
}

std::size_t DopplerInertialFilter::acceptedPointsTotal() const {
  std::size_t total = 0;
  for (const Node& n : nodes_) total += n.sums.n;
  return total;
}

Mat3 DopplerInertialFilter::dopplerInformation(std::size_t k) const {
  return nodes_[k].sums.S[0] / r_doppler_;
}

}  // namespace freeinit
