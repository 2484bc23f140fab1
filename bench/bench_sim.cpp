// Generation speed of the simulator. items/s = generated LiDAR points per second of wall time.
// - BM_Simulate5s: 5 s of a preset at the default density (60,000 points per frame, 10 Hz).
// - BM_RandomScenarios08s/300: 0.8 s (an initialization window and margin) of each of the random
//   scenarios 1..300 at their drawn density, drawing included: the cost of one held-out
//   evaluation set's data (one core).
#include <benchmark/benchmark.h>
#include <freeinit/sim/random_scenario.h>
#include <freeinit/sim/simulator.h>

#include <cstdint>
#include <string>

namespace {

void BM_Simulate5s(benchmark::State& state, const std::string& name) {
  const freeinit::sim::ScenarioConfig config = freeinit::sim::preset(name, 1);
  std::int64_t points = 0;
  for (auto _ : state) {
    const freeinit::sim::Recording rec = freeinit::sim::simulate(config);
    for (const freeinit::LidarFrame& f : rec.frames)
      points += static_cast<std::int64_t>(f.points.size());
    benchmark::DoNotOptimize(rec.frames.data());
  }
  state.SetItemsProcessed(points);
}

void BM_RandomScenarios08s(benchmark::State& state) {
  const auto runs = static_cast<std::uint64_t>(state.range(0));
  std::int64_t points = 0;
  for (auto _ : state) {
    for (std::uint64_t seed = 1; seed <= runs; ++seed) {
      freeinit::sim::ScenarioConfig config = freeinit::sim::randomScenario(seed);
      config.duration = 0.8;
      const freeinit::sim::Recording rec = freeinit::sim::simulate(config);
      for (const freeinit::LidarFrame& f : rec.frames)
        points += static_cast<std::int64_t>(f.points.size());
      benchmark::DoNotOptimize(rec.frames.data());
    }
  }
  state.SetItemsProcessed(points);
  state.counters["s_per_run"] =
      benchmark::Counter(static_cast<double>(runs), benchmark::Counter::kIsIterationInvariantRate |
                                                        benchmark::Counter::kInvert);
}

}  // namespace

BENCHMARK_CAPTURE(BM_Simulate5s, dyna_05, std::string("dyna_05"))
    ->Unit(benchmark::kSecond)
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Simulate5s, dyna_01, std::string("dyna_01"))
    ->Unit(benchmark::kSecond)
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Simulate5s, stat_01, std::string("stat_01"))
    ->Unit(benchmark::kSecond)
    ->Iterations(1);
BENCHMARK(BM_RandomScenarios08s)->Arg(300)->Unit(benchmark::kSecond)->Iterations(1);

BENCHMARK_MAIN();
