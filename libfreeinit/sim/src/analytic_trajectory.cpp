#include <freeinit/sim/analytic_trajectory.h>

#include <cmath>
#include <utility>

namespace freeinit::sim {
namespace {

/// (q, q', q'') of the polynomial sum_k c[k] x^k.
Eigen::Vector3d polyEval(const std::vector<double>& c, double x) {
  Eigen::Vector3d h = Eigen::Vector3d::Zero();
  for (std::size_t i = c.size(); i-- > 0;) {
    h[2] = h[2] * x + 2.0 * h[1];
    h[1] = h[1] * x + h[0];
    h[0] = h[0] * x + c[i];
  }
  return h;
}

/// (w, w', w'') of a sum of sinusoids.
Eigen::Vector3d wavesEval(const std::vector<Sinusoid>& waves, double tau) {
  Eigen::Vector3d h = Eigen::Vector3d::Zero();
  for (const Sinusoid& s : waves) {
    const double w = 2.0 * M_PI * s.freq_hz;
    const double arg = w * tau + s.phase;
    h[0] += s.amplitude * std::sin(arg);
    h[1] += s.amplitude * w * std::cos(arg);
    h[2] -= s.amplitude * w * w * std::sin(arg);
  }
  return h;
}

const ScalarSignal& signalOf(const TrajectoryParams& p, std::size_t i) {
  return i < 3 ? p.pos[i] : p.rpy[i - 3];
}

}  // namespace

Eigen::Vector3d ScalarSignal::eval(double tau) const {
  Eigen::Vector3d h = Eigen::Vector3d::Zero();
  // Horner for the value and both derivatives.
  for (std::size_t i = poly.size(); i-- > 0;) {
    h[2] = h[2] * tau + 2.0 * h[1];
    h[1] = h[1] * tau + h[0];
    h[0] = h[0] * tau + poly[i];
  }
  for (const Sinusoid& s : waves) {
    const double w = 2.0 * M_PI * s.freq_hz;
    const double arg = w * tau + s.phase;
    const double sn = std::sin(arg);
    const double cs = std::cos(arg);
    h[0] += s.amplitude * sn;
    h[1] += s.amplitude * w * cs;
    h[2] -= s.amplitude * w * w * sn;
  }
  return h;
}

AnalyticTrajectory::AnalyticTrajectory(TrajectoryParams params) : params_(std::move(params)) {
  for (std::size_t i = 0; i < 3; ++i) {
    h_at_start_[i] = params_.pos[i].eval(params_.still_until);
    h_at_start_[i + 3] = params_.rpy[i].eval(params_.still_until);
  }
  if (params_.ramp_poly && params_.blend_duration > 0) {
    const double ts = params_.still_until, T = params_.blend_duration;
    for (std::size_t i = 0; i < 6; ++i) {
      const ScalarSignal& h = signalOf(params_, i);
      Ramp& r = ramp_[i];
      // p'(ts + T x) = sum_k k p_k (ts + T x)^(k-1), expanded binomially in x.
      const std::size_t n = h.poly.size();
      r.rate.assign(n > 1 ? n - 1 : 1, 0.0);
      for (std::size_t k = 1; k < n; ++k) {
        double binom = 1;  // C(k-1, j)
        for (std::size_t j = 0; j + 1 <= k; ++j) {
          r.rate[j] += static_cast<double>(k) * h.poly[k] * binom *
                       std::pow(ts, static_cast<double>(k - 1 - j)) *
                       std::pow(T, static_cast<double>(j));
          binom = binom * static_cast<double>(k - 1 - j) / static_cast<double>(j + 1);
        }
      }
      // S(x) p'(ts + T x), S = 10 x^3 - 15 x^4 + 6 x^5, integrated from 0.
      const double S[] = {0, 0, 0, 10, -15, 6};
      std::vector<double> prod(r.rate.size() + 5, 0.0);
      for (std::size_t a = 0; a < 6; ++a)
        for (std::size_t b = 0; b < r.rate.size(); ++b) prod[a + b] += S[a] * r.rate[b];
      r.integral.assign(prod.size() + 1, 0.0);
      for (std::size_t j = 0; j < prod.size(); ++j)
        r.integral[j + 1] = prod[j] / static_cast<double>(j + 1);
      r.integral_at_end = polyEval(r.integral, 1.0)[0];
      r.poly_at_end = polyEval(h.poly, ts + T)[0];
      r.waves_at_start = wavesEval(h.waves, ts)[0];
    }
  }
  mounted_ = params_.R_rb != Mat3::Identity();
  if (params_.heading != 0.0) {
    R_heading_ = Eigen::AngleAxisd(params_.heading, Vec3::UnitZ()).toRotationMatrix();
  }
}

Eigen::Vector3d AnalyticTrajectory::channel(std::size_t i, double tau) const {
  const double start_value = i < 3 ? params_.p_start_w[static_cast<Eigen::Index>(i)]
                                   : params_.rpy_start[static_cast<Eigen::Index>(i - 3)];
  // Gate S(x) = 10x^3 - 15x^4 + 6x^5: S, S', S'' vanish at x = 0 and S', S'' at x = 1, so the
  // standstill joins the motion C2-smoothly.
  double S = 1, dS = 0, ddS = 0;
  const double T = params_.blend_duration;
  if (T > 0) {
    const double x = (tau - params_.still_until) / T;
    if (x <= 0) {
      return Eigen::Vector3d(start_value, 0, 0);
    } else if (params_.ramp_poly) {
      return Eigen::Vector3d(start_value, 0, 0) + rampedChannel(i, tau, x);
    } else if (x < 1) {
      S = x * x * x * (10.0 + x * (-15.0 + 6.0 * x));
      dS = 30.0 * x * x * (1.0 - x) * (1.0 - x) / T;
      ddS = 60.0 * x * (1.0 - x) * (1.0 - 2.0 * x) / (T * T);
    }
  }
  const ScalarSignal& h = i < 3 ? params_.pos[i] : params_.rpy[i - 3];
  const Eigen::Vector3d hv = h.eval(tau);
  const double g = hv[0] - h_at_start_[i][0];
  return Eigen::Vector3d(start_value + S * g, dS * g + S * hv[1],
                         ddS * g + 2.0 * dS * hv[1] + S * hv[2]);
}

Eigen::Vector3d AnalyticTrajectory::rampedChannel(std::size_t i, double tau, double x) const {
  const double T = params_.blend_duration;
  const Ramp& r = ramp_[i];
  const ScalarSignal& h = signalOf(params_, i);
  const Eigen::Vector3d w = wavesEval(h.waves, tau);
  if (x >= 1) {
    const Eigen::Vector3d p = polyEval(h.poly, tau);
    return Eigen::Vector3d(T * r.integral_at_end + p[0] - r.poly_at_end + w[0] - r.waves_at_start,
                           p[1] + w[1], p[2] + w[2]);
  }
  const double S = x * x * x * (10.0 + x * (-15.0 + 6.0 * x));
  const double dS = 30.0 * x * x * (1.0 - x) * (1.0 - x) / T;
  const double ddS = 60.0 * x * (1.0 - x) * (1.0 - 2.0 * x) / (T * T);
  const Eigen::Vector3d q = polyEval(r.rate, x);  // p'(tau) and its x-derivatives
  const double g = w[0] - r.waves_at_start;
  return Eigen::Vector3d(T * polyEval(r.integral, x)[0] + S * g, S * q[0] + dS * g + S * w[1],
                         dS * q[0] + S * q[1] / T + ddS * g + 2.0 * dS * w[1] + S * w[2]);
}

TruthState AnalyticTrajectory::at(double t) const {
  const double tau = t - params_.t0;
  TruthState s;
  s.t = t;
  for (std::size_t i = 0; i < 3; ++i) {
    const Eigen::Vector3d c = channel(i, tau);
    const auto k = static_cast<Eigen::Index>(i);
    s.p_w[k] = c[0];
    s.v_w[k] = c[1];
    s.a_w[k] = c[2];
  }
  const Eigen::Vector3d r = channel(3, tau);  // roll
  const Eigen::Vector3d p = channel(4, tau);  // pitch
  const Eigen::Vector3d y = channel(5, tau);  // yaw
  const double sr = std::sin(r[0]), cr = std::cos(r[0]);
  const double sp = std::sin(p[0]), cp = std::cos(p[0]);
  const double sy = std::sin(y[0]), cy = std::cos(y[0]);
  Mat3 Rx, Ry, Rz;
  Rx << 1, 0, 0, 0, cr, -sr, 0, sr, cr;
  Ry << cp, 0, sp, 0, 1, 0, -sp, 0, cp;
  Rz << cy, -sy, 0, sy, cy, 0, 0, 0, 1;
  s.R_wb = Rz * Ry * Rx;
  // omega_b = roll' e_x + pitch' Rx^T e_y + yaw' Rx^T Ry^T e_z.
  const Vec3 ex(1, 0, 0);
  const Vec3 u(0, cr, -sr);
  const Vec3 w(-sp, sr * cp, cr * cp);
  s.omega_b = r[1] * ex + p[1] * u + y[1] * w;
  // Product rule: u' = roll' du/droll, w' = roll' dw/droll + pitch' dw/dpitch.
  const Vec3 du = r[1] * Vec3(0, -sr, -cr);
  const Vec3 dw = r[1] * Vec3(0, cr * cp, -sr * cp) + p[1] * Vec3(-cp, -sr * sp, -cr * sp);
  s.alpha_b = r[2] * ex + p[2] * u + p[1] * du + y[2] * w + y[1] * dw;
  if (mounted_) {
    // The rig state above, seen from the IMU mounted at R_rb: a constant rotation.
    s.R_wb = s.R_wb * params_.R_rb;
    s.omega_b = params_.R_rb.transpose() * s.omega_b;
    s.alpha_b = params_.R_rb.transpose() * s.alpha_b;
  }
  if (params_.heading != 0.0) {
    s.R_wb = R_heading_ * s.R_wb;
    s.p_w = R_heading_ * s.p_w;
    s.v_w = R_heading_ * s.v_w;
    s.a_w = R_heading_ * s.a_w;
  }
  return s;
}

}  // namespace freeinit::sim
