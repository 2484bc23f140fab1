// freeinit-import-bag on large bags: a dyna_05 recording (vehicle, 60,000 points per frame at
// 10 Hz, the Aeries II-like density) written as a release-layout bag, then imported to a rawlog.
// items/s = LiDAR points imported per second of wall time. BM_ReadBag: the bag side alone (read,
// decode, reorder; no rawlog). Counters: the bag's size and the peak
// resident memory of the import process. The bag is made once (kept in the temp folder) and the
// import is run in a child process, so that neither the simulated recording nor the other length's
// run counts in the peak; the import streams the bag, so its peak must not grow with the bag's
// length (compare the two lengths). BM_CheckBagFile: the structure check readBag runs before
// librosbag opens the bag (bag_guard.h), alone; bytes/s of the bag.
#include <benchmark/benchmark.h>
#include <freeinit/ros1/bag_guard.h>
#include <freeinit/ros1/bag_reader.h>
#include <freeinit/ros1/bag_writer.h>
#include <freeinit/sim/simulator.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "bag_import_app.h"

namespace {

namespace fs = std::filesystem;

// The bag of `seconds` of dyna_05, made once in a child process ("" if that failed).
std::string makeBag(int seconds, const fs::path& dir) {
  fs::create_directories(dir);
  const std::string bag = (dir / ("dyna_05_" + std::to_string(seconds) + "s.bag")).string();
  if (!fs::exists(bag)) {
    const pid_t pid = fork();
    if (pid == 0) {
      auto sc = freeinit::sim::preset("dyna_05", 1);
      sc.duration = seconds;
      const auto rec = freeinit::sim::simulate(sc);
      freeinit::ros1::writeBag(bag, rec.imu, rec.frames, freeinit::ros1::BagWriteOptions());
      _exit(0);
    }
    int status = 0;
    waitpid(pid, &status, 0);
  }
  return fs::exists(bag) ? bag : std::string();
}

// Reading and decoding only (no rawlog written): the bag side of the import.
void BM_ReadBag(benchmark::State& state) {
  const std::string bag = makeBag(static_cast<int>(state.range(0)),
                                  fs::temp_directory_path() / "freeinit_bench_bag_import");
  if (bag.empty()) {
    state.SkipWithError("could not write the bag");
    return;
  }
  std::size_t points = 0;
  for (auto _ : state) {
    freeinit::ros1::BagReadCallbacks cb;
    cb.imu = [](const freeinit::ImuSample&) {};
    cb.frame = [](freeinit::LidarFrame&& f) { benchmark::DoNotOptimize(f.points.data()); };
    points += freeinit::ros1::readBag(bag, freeinit::ros1::BagImportConfig(), cb).points;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(points));
}

void BM_CheckBagFile(benchmark::State& state) {
  const std::string bag = makeBag(static_cast<int>(state.range(0)),
                                  fs::temp_directory_path() / "freeinit_bench_bag_import");
  if (bag.empty()) {
    state.SkipWithError("could not write the bag");
    return;
  }
  for (auto _ : state) freeinit::ros1::checkBagFile(bag);
  state.SetBytesProcessed(static_cast<std::int64_t>(fs::file_size(bag)) * state.iterations());
}

void BM_ImportBag(benchmark::State& state) {
  const fs::path dir = fs::temp_directory_path() / "freeinit_bench_bag_import";
  const std::string bag = makeBag(static_cast<int>(state.range(0)), dir);
  if (bag.empty()) {
    state.SkipWithError("could not write the bag");
    return;
  }
  const std::string ini = (dir / "import.ini").string();
  std::ofstream(ini) << "[bag_import]\n[extrinsics]\nR_bl = 1 0 0 0 1 0 0 0 1\np_bl = 0 0 0\n";
  std::size_t points = 0;
  long peak_kb = 0;
  for (auto _ : state) {
    // The import runs in a child process of this small one: its peak resident memory is the
    // import's (plus the libraries').
    int fd[2];
    if (pipe(fd) != 0) {
      state.SkipWithError("pipe");
      return;
    }
    const pid_t pid = fork();
    if (pid == 0) {
      close(fd[0]);
      freeinit::apps::BagImportApp app;
      app.params.bag = bag;
      app.params.config_file = ini;
      app.params.output = (dir / "out.rawlog").string();
      app.params.progress = false;
      std::ostringstream log;
      app.run(log);
      const std::size_t n = app.summary.points;
      _exit(write(fd[1], &n, sizeof(n)) == sizeof(n) ? 0 : 1);
    }
    close(fd[1]);
    std::size_t n = 0;
    const bool got = read(fd[0], &n, sizeof(n)) == sizeof(n);
    close(fd[0]);
    int status = 0;
    rusage u{};
    wait4(pid, &status, 0, &u);
    if (!got || status != 0) {
      state.SkipWithError("the import failed");
      return;
    }
    points += n;
    peak_kb = std::max(peak_kb, u.ru_maxrss);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(points));
  state.counters["bag_MB"] = static_cast<double>(fs::file_size(bag)) / 1e6;
  state.counters["peak_rss_MB"] = static_cast<double>(peak_kb) / 1e3;
}

}  // namespace

BENCHMARK(BM_CheckBagFile)->Arg(5)->Unit(benchmark::kSecond)->Iterations(3)->UseRealTime();
BENCHMARK(BM_ReadBag)->Arg(5)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
BENCHMARK(BM_ImportBag)->Arg(5)->Arg(20)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

BENCHMARK_MAIN();
