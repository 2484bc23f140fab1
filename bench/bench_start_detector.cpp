// Speed of the start decision alone, on one core:
//   BM_DecideStart/<preset>  decideStart over the start span (the first 0.1 s of the window)
//                            of each preset at the default configuration, the returns prepared as
//                            the pipeline prepares them: the window starts at the first IMU sample
//                            at or after the first LiDAR point, the span's usable returns are
//                            thinned evenly to [start] points. Time per decision in ms; target
//                            on dyna_05: <= 2 ms. Counters: points = returns handed to the
//                            decision, hypotheses = motions it refined and kept, kind = the
//                            decision (StartDecision::Kind as a number).
// The recordings are simulated and the returns prepared once, outside the timed loop.
#include <benchmark/benchmark.h>
#include <freeinit/config.h>
#include <freeinit/sim/simulator.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "joint/start_detector.h"

namespace {

/// The decision's input as the pipeline builds it from a recording.
struct StartInput {
  freeinit::sim::Recording rec;
  std::size_t k_first = 0, k_last = 0;
  std::vector<freeinit::StartPoint> points;
  freeinit::StartDetectorParams params;
};

/// The pipeline's test of a return (finite, within the configured range).
bool usable(const freeinit::DopplerPoint& p, const freeinit::DopplerParams& dp) {
  if (!p.p_l.allFinite() || !std::isfinite(p.doppler) || !std::isfinite(p.time_offset))
    return false;
  const double r = p.p_l.norm();
  return r > 0 && r >= dp.min_range && r <= dp.max_range;
}

StartInput prepare(const std::string& name) {
  StartInput in;
  freeinit::sim::ScenarioConfig sc = freeinit::sim::preset(name, 1);
  sc.duration = 0.8;  // as bench_free_init: the window and the start span
  in.rec = freeinit::sim::simulate(sc);
  const freeinit::FreeInitConfig cfg;
  const freeinit::DopplerParams& dp = cfg.doppler;
  const auto& imu = in.rec.imu;
  // Point times in time order (frames are, and their points within them).
  struct Timed {
    double t;
    const freeinit::DopplerPoint* p;
  };
  std::vector<Timed> all;
  for (const auto& f : in.rec.frames)
    for (const auto& p : f.points)
      all.push_back({f.stamp + static_cast<double>(p.time_offset), &p});
  if (all.empty() || imu.empty()) return in;
  const freeinit::StartSpan start = freeinit::startSpan(imu, all.front().t, cfg);
  if (!start.valid) return in;
  const std::size_t k = start.k_first, k_last = start.k_last;
  const double t_ref = imu[k].t;
  const double t_end = imu[k_last].t;
  std::size_t n_usable = 0;
  for (const Timed& q : all)
    if (q.t <= t_end && q.t >= t_ref && usable(*q.p, dp)) ++n_usable;
  const std::size_t thin =
      std::max<std::size_t>(1, n_usable / static_cast<std::size_t>(cfg.start.points));
  std::size_t n = 0;
  for (const Timed& q : all) {
    if (q.t > t_end) break;
    if (q.t < t_ref || !usable(*q.p, dp)) continue;
    if (n++ % thin != 0) continue;
    in.points.push_back({q.t - t_ref, q.p->p_l.cast<double>().normalized(), q.p->doppler});
  }
  in.k_first = k;
  in.k_last = k_last;
  in.params = freeinit::startDetectorParams(cfg);
  return in;
}

void BM_DecideStart(benchmark::State& state, const std::string& name) {
  const StartInput in = prepare(name);
  const freeinit::FreeInitConfig cfg;
  freeinit::StartDecision d;
  for (auto _ : state) {
    d = freeinit::decideStart(in.rec.imu, in.k_first, in.k_last, in.points, in.rec.extrinsics,
                              cfg.imu.gyro_bias_prior, in.params);
    benchmark::DoNotOptimize(d.chosen.v_b0.data());
  }
  state.counters["points"] = static_cast<double>(in.points.size());
  state.counters["hypotheses"] = static_cast<double>(d.hypotheses.size());
  state.counters["kind"] = static_cast<double>(static_cast<int>(d.kind));
}

}  // namespace

BENCHMARK_CAPTURE(BM_DecideStart, dyna_05, std::string("dyna_05"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_DecideStart, stat_02, std::string("stat_02"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_DecideStart, dyna_01, std::string("dyna_01"))->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
