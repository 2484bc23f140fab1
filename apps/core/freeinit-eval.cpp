// Runs Free-Init and the baselines on simulated presets and prints their errors against ground
// truth. Usage: freeinit-eval [--seeds N] [--stride K] [--points P] [preset ...]
#include <freeinit/baselines.h>
#include <freeinit/free_init.h>
#include <freeinit/sim/evaluation.h>
#include <freeinit/sim/simulator.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <random>
#include <string>
#include <vector>

namespace {

void printRow(const char* method, const std::string& preset, std::uint64_t seed,
              const freeinit::InitResult& r, const freeinit::sim::Recording& rec, double ms) {
  const auto e = freeinit::sim::evaluate(r.state, rec);
  if (!e.valid) {
    std::printf("%-8s %-18s %3llu  FAILED: %s\n", method, preset.c_str(),
                static_cast<unsigned long long>(seed), r.state.message.c_str());
    return;
  }
  std::printf(
      "%-8s %-18s %3llu  |v|=%6.2f dv=%7.4f  dg=%6.3f deg (ba_h %5.3f)  dbg=%7.5f  dba=%6.3f "
      "(vert %6.3f)  nees v=%6.2f tilt=%6.2f bg=%6.2f ba=%6.2f  %6.1f ms  used=%zu rej=%zu\n",
      method, preset.c_str(), static_cast<unsigned long long>(seed), e.vel_b_true_norm, e.vel_b,
      e.gravity_deg, e.gravity_deg_from_bias, e.gyro_bias, e.accel_bias, e.accel_bias_vertical,
      e.nees_vel_b, e.nees_tilt, e.nees_gyro_bias, e.nees_accel_bias, ms, r.diag.points_used,
      r.diag.points_rejected);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    int seeds = 3, stride = 0, points = 0;  // stride 0: the configuration default
    double duration = 1.2;
    bool baselines = true, trace = false, zero_bg = false;
    int passes = -1;
    double tau = -1, gyro_prior = 0;
    bool no_db = false;
    std::vector<std::string> presets;
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--seeds" && i + 1 < argc) seeds = std::atoi(argv[++i]);
      else if (a == "--stride" && i + 1 < argc) stride = std::atoi(argv[++i]);
      else if (a == "--points" && i + 1 < argc) points = std::atoi(argv[++i]);
      else if (a == "--duration" && i + 1 < argc) duration = std::atof(argv[++i]);
      else if (a == "--no-baselines") baselines = false;
      else if (a == "--trace") trace = true;
      else if (a == "--zero-gyro-bias") zero_bg = true;
      else if (a == "--passes" && i + 1 < argc) passes = std::atoi(argv[++i]);
      else if (a == "--tau" && i + 1 < argc) tau = std::atof(argv[++i]);
      else if (a == "--no-gyro-bias-estimate") no_db = true;
      else if (a == "--gyro-prior" && i + 1 < argc) gyro_prior = std::atof(argv[++i]);
      else presets.push_back(a);
    }
    if (presets.empty()) presets = freeinit::sim::presetNames();
    for (const auto& name : presets) {
      for (int s = 1; s <= seeds; ++s) {
        auto sc = freeinit::sim::preset(name, static_cast<std::uint64_t>(s));
        sc.duration = duration;
        if (points > 0) sc.points_per_frame = points;
        if (zero_bg) {
          sc.random_biases = false;
          sc.b_g.setZero();
          sc.b_a = freeinit::Vec3(0.1, -0.08, 0.05);
        }
        const auto rec = freeinit::sim::simulate(sc);
        freeinit::FreeInitConfig cfg;
        cfg.extrinsics = rec.extrinsics;
        if (stride > 0) cfg.velocimeter.point_stride = stride;
        if (passes >= 0) cfg.window.refinement_passes = passes;
        if (tau >= 0) cfg.gravity.velocity_error_correlation_time = tau;
        if (no_db) cfg.gravity.estimate_gyro_bias = false;
        if (gyro_prior > 0) {
          // A gyro-bias prior as from a static calibration: the truth plus noise of that std.
          std::mt19937_64 rng(1000 + static_cast<std::uint64_t>(s));
          std::normal_distribution<double> n01;
          cfg.velocimeter.gyro_bias_prior =
              rec.b_g + gyro_prior * freeinit::Vec3(n01(rng), n01(rng), n01(rng));
          cfg.velocimeter.gyro_bias_sigma0 = gyro_prior;
        }
        const auto t0 = std::chrono::steady_clock::now();
        const auto r = freeinit::FreeInit::run(cfg, rec.imu, rec.frames);
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count();
        printRow("freeinit", name, s, r, rec, ms);
        if (trace) {
          for (std::size_t i = 0; i < r.velocities.size(); i += 5) {
            const auto& v = r.velocities[i];
            const auto tr = rec.truth(v.t);
            const freeinit::Vec3 vb = tr.R_wb.transpose() * tr.v_w;
            const freeinit::Vec3 dv = v.v_b - vb;
            const freeinit::Vec3 dw = v.omega_b - tr.omega_b;
            std::printf("  t=%.3f vb_true=(%6.2f %6.2f %6.2f) dv=(%7.3f %7.3f %7.3f) dw=(%6.3f %6.3f %6.3f) sig=%.3f st=%d\n",
                        v.t - rec.config.t0, vb.x(), vb.y(), vb.z(), dv.x(), dv.y(), dv.z(),
                        dw.x(), dw.y(), dw.z(), v.sigma_v_b.norm(), v.stationary ? 1 : 0);
          }
        }
        if (baselines) {
          printRow("fastlio2", name, s, freeinit::baselines::fastLio2(rec.imu), rec, 0);
          printRow("doppler", name, s,
                   freeinit::baselines::dopplerLeastSquares(rec.imu, rec.frames, rec.extrinsics),
                   rec, 0);
        }
      }
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "freeinit-eval: %s\n", e.what());
    return 1;
  }
}
