// Generation speed of the simulator: 5 s of a preset at the default density (60,000 points per
// frame, 10 Hz). items/s = generated LiDAR points per second of wall time.
#include <freeinit/sim/simulator.h>

#include <benchmark/benchmark.h>

#include <string>

namespace {

void BM_Simulate5s(benchmark::State& state, const std::string& name) {
  const freeinit::sim::ScenarioConfig config = freeinit::sim::preset(name, 1);
  std::int64_t points = 0;
  for (auto _ : state) {
    const freeinit::sim::Recording rec = freeinit::sim::simulate(config);
    for (const freeinit::LidarFrame& f : rec.frames) points += static_cast<std::int64_t>(f.points.size());
    benchmark::DoNotOptimize(rec.frames.data());
  }
  state.SetItemsProcessed(points);
}

}  // namespace

BENCHMARK_CAPTURE(BM_Simulate5s, dyna_05, std::string("dyna_05"))->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_Simulate5s, dyna_01, std::string("dyna_01"))->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_Simulate5s, stat_01, std::string("stat_01"))->Unit(benchmark::kSecond)->Iterations(1);

BENCHMARK_MAIN();
