// simulate(): IMU samples and Doppler LiDAR frames from an exact trajectory and scene.
//
// LiDAR raster (Aeva Aeries II-like, non-rotating): N = points_per_frame points per frame are
// measured one after the other at uniform spacing over the frame period T = 1/frame_rate,
// point i (0..N-1) at time_offset = i T / N. Scan slot s (0..L-1, in time order) holds points
// floor(s N / L) .. floor((s+1) N / L) - 1 and measures line k = line_order(s) (0 = top) at
// elevation vfov/2 - (k + 0.5) vfov / L; within a slot the azimuth sweeps uniformly from -hfov/2
// to +hfov/2 (bin centres), on odd slots back again when line_direction is Alternating. LiDAR
// frame: x forward, y left, z up; direction (cos e cos a, cos e sin a, sin e). Rays with no hit in
// [min_range, max_range] are dropped, so frames hold fewer than N points. The recorded stamp of a
// frame is its true start plus lidar_time_offset (the LiDAR clock's offset).
#include <freeinit/sim/scene.h>
#include <freeinit/sim/simulator.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "random_stream.h"

namespace freeinit::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

/// LiDAR pose and velocity at one instant, all in w.
struct LidarState {
  Mat3 R_wl;
  Vec3 p_wl;
  Vec3 v_wl;  ///< [m/s] velocity of the LiDAR origin
};

LidarState lidarState(const TruthState& s, const Extrinsics& e) {
  LidarState l;
  l.R_wl = s.R_wb * e.R_bl;
  l.p_wl = s.p_w + s.R_wb * e.p_bl;
  l.v_wl = s.v_w + s.R_wb * s.omega_b.cross(e.p_bl);
  return l;
}

double rotationAngle(const Mat3& R) {
  return std::acos(std::clamp(0.5 * (R.trace() - 1.0), -1.0, 1.0));
}

void drawBiases(const ScenarioConfig& c, Recording& rec) {
  if (!c.random_biases) {
    rec.b_g = c.b_g;
    rec.b_a = c.b_a;
    return;
  }
  std::mt19937_64 rng = detail::randomStream(c.seed, detail::Stream::Biases);
  std::uniform_real_distribution<double> gyro(0.005, 0.02), accel(0.02, 0.15), sign(-1.0, 1.0);
  for (int k = 0; k < 3; ++k) {
    const double g = gyro(rng);
    rec.b_g[k] = sign(rng) < 0 ? -g : g;
  }
  for (int k = 0; k < 3; ++k) {
    const double a = accel(rng);
    rec.b_a[k] = sign(rng) < 0 ? -a : a;
  }
}

void simulateImu(const ScenarioConfig& c, Recording& rec) {
  std::mt19937_64 rng = detail::randomStream(c.seed, detail::Stream::Imu);
  std::normal_distribution<double> n01(0.0, 1.0);
  const Vec3 gyro_sigma = c.gyroSigmaPerAxis(), accel_sigma = c.accelSigmaPerAxis();
  const long n = static_cast<long>(std::floor(c.duration * c.imu_rate + 1e-9)) + 1;
  rec.imu.reserve(static_cast<std::size_t>(n));
  for (long k = 0; k < n; ++k) {
    const double t = c.t0 + static_cast<double>(k) / c.imu_rate;
    const TruthState s = rec.trajectory->at(t);
    ImuSample m;
    m.t = t;
    m.gyro = s.omega_b + rec.b_g;
    m.accel = s.R_wb.transpose() * (s.a_w - rec.g_w) + rec.b_a;
    for (int i = 0; i < 3; ++i) m.gyro[i] += gyro_sigma[i] * n01(rng);
    for (int i = 0; i < 3; ++i) m.accel[i] += accel_sigma[i] * n01(rng);
    rec.imu.push_back(m);
  }
}

/// Indices of primitives that may be hit by any ray of the frame (range culling).
std::vector<int> frameCandidates(const Scene& scene, const ScenarioConfig& c, const LidarState& mid,
                                 double path_radius, double tau_mid, double half_period) {
  std::vector<int> out;
  const auto& prims = scene.primitives();
  for (std::size_t i = 0; i < prims.size(); ++i) {
    const Primitive& p = prims[i];
    const double r = p.boundingRadius() + p.v_w.norm() * half_period + path_radius;
    if ((p.centerAt(tau_mid) - mid.p_wl).norm() - r < c.max_range)
      out.push_back(static_cast<int>(i));
  }
  return out;
}

/// Indices of primitives whose bounding sphere can meet the fan of rays of one line.
/// A direction of elevation e is at least |e - e_c| away from a direction of elevation e_c, and
/// every ray of the line is within acos(cos e cos(hfov/2)) of the LiDAR x axis.
void lineCandidates(const Scene& scene, const std::vector<int>& frame_cands,
                    const ScenarioConfig& c, const LidarState& mid, double elevation,
                    double ang_margin, double pos_margin, double tau_mid, double half_dt,
                    std::vector<int>& out) {
  out.clear();
  const double fan = std::acos(std::cos(elevation) * std::cos(0.5 * c.hfov_deg * kDeg));
  const auto& prims = scene.primitives();
  for (int i : frame_cands) {
    const Primitive& p = prims[static_cast<std::size_t>(i)];
    const double r = p.boundingRadius() + p.v_w.norm() * half_dt + pos_margin;
    const Vec3 c_l = mid.R_wl.transpose() * (p.centerAt(tau_mid) - mid.p_wl);
    const double d = c_l.norm();
    if (d <= r) {
      out.push_back(i);
      continue;
    }
    if (d - r > c.max_range) continue;
    const double ang_r = std::asin(r / d) + ang_margin;
    const double e_c = std::atan2(c_l.z(), std::hypot(c_l.x(), c_l.y()));
    if (std::abs(e_c - elevation) > ang_r) continue;
    if (std::acos(std::clamp(c_l.x() / d, -1.0, 1.0)) > fan + ang_r) continue;
    out.push_back(i);
  }
}

/// The line measured in scan slot s of L.
int lineOfSlot(LineOrder order, int s, int L) {
  switch (order) {
    case LineOrder::TopDown:
      return s;
    case LineOrder::BottomUp:
      return L - 1 - s;
    case LineOrder::Interleaved: {
      const int n_even = (L + 1) / 2;
      return s < n_even ? 2 * s : 2 * (s - n_even) + 1;
    }
  }
  return s;
}

void simulateLidar(const ScenarioConfig& c, Recording& rec, const SimulationProgress& progress) {
  std::mt19937_64 rng = detail::randomStream(c.seed, detail::Stream::Lidar);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const Scene& scene = *rec.scene;
  const Trajectory& traj = *rec.trajectory;
  const Extrinsics& ext = rec.extrinsics;
  const double T = 1.0 / c.frame_rate;
  const long n_frames = static_cast<long>(frameCount(c));
  const long N = c.points_per_frame;
  const int L = c.lines;
  const double dt = T / static_cast<double>(std::max<long>(N, 1));
  const double hfov = c.hfov_deg * kDeg, vfov = c.vfov_deg * kDeg;
  constexpr double kOutlierSpan = 15.0;  // [m/s] gross outliers are uniform in +-15 m/s
  std::vector<int> line_cands;
  rec.frames.reserve(static_cast<std::size_t>(n_frames));
  rec.labels.reserve(static_cast<std::size_t>(n_frames));
  for (long f = 0; f < n_frames; ++f) {
    LidarFrame frame;
    std::vector<PointLabel> labels;
    frame.stamp = c.t0 + static_cast<double>(f) / c.frame_rate;
    frame.points.reserve(static_cast<std::size_t>(N));
    labels.reserve(static_cast<std::size_t>(N));
    const double tau_f = frame.stamp - c.t0;
    const LidarState l0 = lidarState(traj.at(frame.stamp), ext);
    const LidarState lm = lidarState(traj.at(frame.stamp + 0.5 * T), ext);
    const LidarState l1 = lidarState(traj.at(frame.stamp + T), ext);
    const double path_radius =
        std::max((l0.p_wl - lm.p_wl).norm(), (l1.p_wl - lm.p_wl).norm()) + 0.5;
    const std::vector<int> frame_cands =
        frameCandidates(scene, c, lm, path_radius, tau_f + 0.5 * T, 0.5 * T);
    for (int slot = 0; slot < L; ++slot) {
      const int k = lineOfSlot(c.line_order, slot, L);
      const bool backwards = c.line_direction == LineDirection::Alternating && slot % 2 == 1;
      const long i_begin = static_cast<long>(slot) * N / L;
      const long i_end = static_cast<long>(slot + 1) * N / L;
      const long n_line = i_end - i_begin;
      if (n_line <= 0) continue;
      const double elevation = 0.5 * vfov - (k + 0.5) * vfov / L;
      const double ce = std::cos(elevation), se = std::sin(elevation);
      // Culling margins from the actual motion during the line.
      const double ta = static_cast<double>(i_begin) * dt, tb = static_cast<double>(i_end) * dt;
      const LidarState la = lidarState(traj.at(frame.stamp + ta), ext);
      const LidarState lb = lidarState(traj.at(frame.stamp + tb), ext);
      const LidarState lmid = lidarState(traj.at(frame.stamp + 0.5 * (ta + tb)), ext);
      const double ang_margin = std::max(rotationAngle(la.R_wl.transpose() * lmid.R_wl),
                                         rotationAngle(lb.R_wl.transpose() * lmid.R_wl)) +
                                2e-3;
      const double pos_margin =
          std::max((la.p_wl - lmid.p_wl).norm(), (lb.p_wl - lmid.p_wl).norm()) + 0.05;
      lineCandidates(scene, frame_cands, c, lmid, elevation, ang_margin, pos_margin,
                     tau_f + 0.5 * (ta + tb), 0.5 * (tb - ta), line_cands);
      if (line_cands.empty()) continue;
      for (long j = 0; j < n_line; ++j) {
        const long i = i_begin + j;
        const float time_offset = static_cast<float>(static_cast<double>(i) * dt);
        const double t = frame.stamp + static_cast<double>(time_offset);
        const double s = (static_cast<double>(j) + 0.5) / static_cast<double>(n_line);
        const double az = (backwards ? 0.5 - s : -0.5 + s) * hfov;
        const Vec3 d_l(ce * std::cos(az), ce * std::sin(az), se);
        const TruthState st = traj.at(t);
        const LidarState ls = lidarState(st, ext);
        const Vec3 d_w = ls.R_wl * d_l;
        RayHit hit;
        if (!scene.castRay(ls.p_wl, d_w, t - c.t0, c.max_range, line_cands, hit)) continue;
        if (hit.range < c.min_range) continue;
        const Primitive& prim = scene.primitives()[static_cast<std::size_t>(hit.primitive)];
        // Range rate of the point relative to the LiDAR (exact, including the lever arm).
        const double doppler_true = d_w.dot(prim.v_w - ls.v_wl);
        PointLabel label = prim.isDynamic() ? PointLabel::Dynamic : PointLabel::Static;
        const double range = hit.range + c.range_sigma * n01(rng);
        double doppler = doppler_true + c.doppler_sigma * n01(rng);
        if (u01(rng) < c.outlier_ratio) {
          doppler = kOutlierSpan * (2.0 * u01(rng) - 1.0);
          label = PointLabel::Outlier;
        }
        DopplerPoint pt;
        pt.p_l = (range * d_l).cast<float>();
        pt.doppler = static_cast<float>(doppler);
        pt.time_offset = time_offset;
        pt.intensity = static_cast<float>(prim.reflectivity * std::abs(hit.n_w.dot(d_w)));
        pt.line = static_cast<std::uint16_t>(k);
        frame.points.push_back(pt);
        labels.push_back(label);
      }
    }
    frame.stamp += c.lidar_time_offset;
    rec.frames.push_back(std::move(frame));
    rec.labels.push_back(std::move(labels));
    if (progress) progress(rec.frames.size(), static_cast<std::size_t>(n_frames));
  }
}

}  // namespace

std::size_t frameCount(const ScenarioConfig& config) {
  return static_cast<std::size_t>(std::floor(config.duration * config.frame_rate + 1e-9));
}

Recording simulate(const ScenarioConfig& config, const SimulationProgress& progress) {
  try {
    validateScenario(config);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("freeinit::sim::simulate: ") + e.what());
  }
  Recording rec;
  rec.config = config;
  rec.g_w = Vec3(0, 0, -kGravity);
  const auto traj = makeTrajectory(config);
  rec.trajectory = traj;
  rec.scene = makeScene(config, *traj);
  rec.extrinsics = makeExtrinsics(config);
  rec.declared_extrinsics = declaredExtrinsics(config, rec.extrinsics);
  rec.lidar_time_offset = config.lidar_time_offset;
  drawBiases(config, rec);
  simulateImu(config, rec);
  simulateLidar(config, rec, progress);
  return rec;
}

}  // namespace freeinit::sim
