// Speed of the Cramer-Rao bound of one run (freeinit/eval), on one core:
//   BM_BoundOfWindow  sim::cramerRaoBound over a window of a preset recording at the default
//                     60,000 points per frame: the truth at every IMU sample, every static point's
//                     Doppler aggregated per interval, the information recursion and the solve.
//                     items_per_second = points/s. Target: a 0.5 s window (~280,000 points,
//                     100 IMU intervals) in a few milliseconds, so that 300 runs cost seconds.
//   BM_BoundCompute   compute() alone (the recursion over the intervals and the solve), with the
//                     IMU noise as process noise; argument: the number of IMU intervals.
// The recordings are simulated once, outside the timed loops.
#include <benchmark/benchmark.h>
#include <freeinit/config.h>
#include <freeinit/sim/evaluation.h>
#include <freeinit/sim/presets.h>
#include <freeinit/sim/simulator.h>

#include <map>
#include <string>
#include <vector>

namespace {

const freeinit::sim::Recording& recording(const std::string& name) {
  static std::map<std::string, freeinit::sim::Recording> cache;  // benchmark fixture data only
  auto it = cache.find(name);
  if (it == cache.end()) {
    auto sc = freeinit::sim::preset(name, 1);
    sc.duration = 1.2;
    it = cache.emplace(name, freeinit::sim::simulate(sc)).first;
  }
  return it->second;
}

void BM_BoundOfWindow(benchmark::State& state, const std::string& name) {
  const auto& rec = recording(name);
  const auto model = freeinit::sim::boundModel(rec, freeinit::FreeInitConfig{});
  const auto samples = static_cast<std::size_t>(state.range(0));
  const double t0 = rec.imu.front().t, t1 = rec.imu[samples].t;
  std::size_t points = 0;
  for (auto _ : state) {
    const auto b = freeinit::sim::cramerRaoBound(rec, model, t0, t1);
    benchmark::DoNotOptimize(b.velocity);
    points = b.measurements;
  }
  state.counters["points"] = static_cast<double>(points);
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * points));
  state.SetLabel(name);
}
BENCHMARK_CAPTURE(BM_BoundOfWindow, dyna_01, std::string("dyna_01"))
    ->Arg(100)
    ->Arg(200)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BoundOfWindow, stat_02, std::string("stat_02"))
    ->Arg(100)
    ->Unit(benchmark::kMillisecond);

void BM_BoundCompute(benchmark::State& state) {
  const auto& rec = recording("dyna_04");
  const auto model = freeinit::sim::boundModel(rec, freeinit::FreeInitConfig{});
  std::vector<freeinit::eval::KinematicTruth> nodes;
  for (std::int64_t k = 0; k <= state.range(0); ++k) {
    const double t = rec.imu[static_cast<std::size_t>(k)].t;
    const auto s = rec.truth(t);
    nodes.push_back({t, s.R_wb, s.v_w, s.a_w, s.omega_b});
  }
  freeinit::eval::CramerRaoBound bound(model, nodes);
  for (const auto& f : rec.frames)
    for (const auto& p : f.points)
      bound.addDoppler(f.stamp + static_cast<double>(p.time_offset), p.p_l.cast<double>());
  for (auto _ : state) benchmark::DoNotOptimize(bound.compute().velocity);
}
BENCHMARK(BM_BoundCompute)->Arg(100)->Arg(200)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
