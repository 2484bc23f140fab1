// Speed and memory of the estimator core, on one core:
//   BM_JointForwardPass    the joint estimator's forward pass alone, with and without the returns
//                          (their difference: the per-point stage; items_per_second = returns/s),
//                          each node's returns given as the arrays the pipeline's recorder lays
//                          out (setReturns: the filter's stage, without the layout).
//   BM_VelocimeterDoppler  Doppler point updates per second through the velocimeter alone
//                          (propagate + updateDoppler, gyro updates interleaved at 200 Hz as in the
//                          real stream). items_per_second = points/s; target >= 3,000,000.
//   BM_FreeInitRun         one whole initialization, FreeInit::run (velocimeter, integration,
//                          mapping, solve, all passes) over 0.8 s of each preset at the default
//                          60,000 points per frame; the window is the default 0.5 s (100 IMU
//                          samples); the default uses every point. Time per initialization in
//                          ms (docs/performance.md: the targets and where the time goes).
//                          Counters: peak_heap_bytes = peak extra heap during one run (including
//                          the returned result), result_bytes = heap the result still holds,
//                          allocs = allocations per run, ms_to_result = the time the call that
//                          closes the window takes (what an online user waits for: the state),
//                          ms_map = the map built after it (FreeInit::result()). Sweeps on
//                          dyna_05: every 2nd, 4th, 8th point (_stride2..8: the cost of a return
//                          against that of the window) and the IMU at 400 and 1000 Hz instead
//                          of 200 (_imu400.., _imu1000.., _imu2000..: one filter node per IMU
//                          sample; _imu<rate>_nodes200..: nodes at 200 Hz, [joint] node_rate).
// The recordings are simulated once, outside the timed loops.
// BM_FreeInitRun's updates_per_s_of_data is the velocimeter's output rate: its state updates per
// second of recording (the paper reports > 10 kHz).
#include <benchmark/benchmark.h>
#include <freeinit/free_init.h>
#include <freeinit/sim/simulator.h>
#include <malloc.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <new>
#include <string>
#include <vector>

#include "joint/doppler_inertial_filter.h"
#include "paper/velocimeter.h"

// ---------------------------------------------------------------------------------------------
// Heap accounting: the global allocation functions of this executable count live and peak bytes
// (usable sizes as reported by glibc). Single-threaded benchmarks; the counters are plain.
namespace {

struct HeapStats {
  std::int64_t live = 0;
  std::int64_t peak = 0;
  std::int64_t allocs = 0;
};
HeapStats g_heap;

void* countedAlloc(std::size_t n) {
  void* p = std::malloc(n == 0 ? 1 : n);
  if (p == nullptr) throw std::bad_alloc();
  g_heap.live += static_cast<std::int64_t>(malloc_usable_size(p));
  g_heap.peak = std::max(g_heap.peak, g_heap.live);
  ++g_heap.allocs;
  return p;
}

void* countedAlignedAlloc(std::size_t n, std::align_val_t al) {
  const std::size_t a = static_cast<std::size_t>(al);
  void* p = std::aligned_alloc(a, (std::max<std::size_t>(n, 1) + a - 1) / a * a);
  if (p == nullptr) throw std::bad_alloc();
  g_heap.live += static_cast<std::int64_t>(malloc_usable_size(p));
  g_heap.peak = std::max(g_heap.peak, g_heap.live);
  ++g_heap.allocs;
  return p;
}

void countedFree(void* p) noexcept {
  if (p == nullptr) return;
  g_heap.live -= static_cast<std::int64_t>(malloc_usable_size(p));
  std::free(p);
}

}  // namespace

void* operator new(std::size_t n) { return countedAlloc(n); }
void* operator new[](std::size_t n) { return countedAlloc(n); }
void* operator new(std::size_t n, std::align_val_t al) { return countedAlignedAlloc(n, al); }
void* operator new[](std::size_t n, std::align_val_t al) { return countedAlignedAlloc(n, al); }
void operator delete(void* p) noexcept { countedFree(p); }
void operator delete[](void* p) noexcept { countedFree(p); }
void operator delete(void* p, std::size_t) noexcept { countedFree(p); }
void operator delete[](void* p, std::size_t) noexcept { countedFree(p); }
void operator delete(void* p, std::align_val_t) noexcept { countedFree(p); }
void operator delete[](void* p, std::align_val_t) noexcept { countedFree(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { countedFree(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { countedFree(p); }

namespace {

constexpr double kSimDuration = 0.8;  ///< [s] covers the 0.5 s window and the bootstrap

/// One simulated recording per preset (seed 1) and IMU rate (0: the preset's), made on first use.
const freeinit::sim::Recording& recording(const std::string& name, double imu_rate = 0) {
  static std::map<std::pair<std::string, double>, freeinit::sim::Recording> cache;
  auto it = cache.find({name, imu_rate});
  if (it == cache.end()) {
    freeinit::sim::ScenarioConfig sc = freeinit::sim::preset(name, 1);
    sc.duration = kSimDuration;
    if (imu_rate > 0) sc.imu_rate = imu_rate;  // the same noise per sample
    it = cache.emplace(std::make_pair(name, imu_rate), freeinit::sim::simulate(sc)).first;
  }
  return it->second;
}

/// The velocimeter's input as one time-ordered stream: points in range and gyro samples.
struct Stream {
  struct Event {
    double t = 0;           ///< [s] relative to the first IMU sample
    std::int32_t imu = -1;  ///< IMU index for a gyro event, -1 for a point
    Eigen::Vector3f p_l = Eigen::Vector3f::Zero();
    double doppler = 0;
  };
  std::vector<Event> events;
  std::int64_t points = 0;
};

Stream makeStream(const freeinit::sim::Recording& rec, const freeinit::DopplerParams& dp) {
  Stream s;
  const double t0 = rec.imu.front().t;
  std::vector<Stream::Event> pts;
  for (const auto& f : rec.frames)
    for (const auto& p : f.points) {
      const double r = p.p_l.norm();
      const double t = f.stamp + p.time_offset - t0;
      if (t < 0 || r < dp.min_range || r > dp.max_range) continue;
      pts.push_back({t, -1, p.p_l, p.doppler});
    }
  // Keep the points within the IMU span, merge in the gyro samples.
  const double t_last = rec.imu.back().t - t0;
  std::size_t k = 0;
  for (const auto& e : pts) {
    if (e.t > t_last) break;
    while (k < rec.imu.size() && rec.imu[k].t - t0 < e.t) {
      s.events.push_back(
          {rec.imu[k].t - t0, static_cast<std::int32_t>(k), Eigen::Vector3f::Zero(), 0});
      ++k;
    }
    s.events.push_back(e);
    ++s.points;
  }
  return s;
}

void BM_VelocimeterDoppler(benchmark::State& state, const std::string& name) {
  const freeinit::sim::Recording& rec = recording(name);
  const freeinit::FreeInitConfig cfg;
  const Stream stream = makeStream(rec, cfg.doppler);
  const auto& imu = rec.imu;
  std::int64_t accepted = 0;
  for (auto _ : state) {
    freeinit::Velocimeter div(freeinit::velocimeterParams(cfg), rec.extrinsics);
    // Started from the true LiDAR velocity with a loose covariance (the bootstrap's job).
    const freeinit::sim::TruthState x0 = rec.truth(imu.front().t);
    const freeinit::Vec3 v_b0 = x0.R_wb.transpose() * x0.v_w;
    const freeinit::Vec3 v_l0 =
        rec.extrinsics.R_bl.transpose() * (v_b0 + x0.omega_b.cross(rec.extrinsics.p_bl));
    div.start(0.0, v_l0, freeinit::Mat3::Identity() * 0.01, imu.front().gyro);
    for (const Stream::Event& e : stream.events) {
      div.propagate(e.t);
      if (e.imu < 0) {
        accepted += div.updateDoppler(e.p_l, e.doppler).accepted ? 1 : 0;
      } else {
        const std::size_t k = static_cast<std::size_t>(e.imu);
        const bool has_next = k + 1 < imu.size();
        div.updateGyro(imu[k].gyro, has_next ? imu[k + 1].gyro : imu[k].gyro,
                       has_next ? imu[k + 1].t - imu[k].t : 0.0);
      }
    }
    benchmark::DoNotOptimize(div.v_b().data());
  }
  state.SetItemsProcessed(state.iterations() * stream.points);
  state.counters["points"] = static_cast<double>(stream.points);
  state.counters["accepted_frac"] =
      static_cast<double>(accepted) / static_cast<double>(state.iterations() * stream.points);
}

/// stride 0: the default configuration as it is; imu_rate 0: the preset's; node_rate: [joint]
/// node_rate (0: one filter node per IMU sample, the rate then sets the nodes of the window;
/// < 0: the configuration's default).
void BM_FreeInitRun(benchmark::State& state, const std::string& name, int stride, double imu_rate,
                    double node_rate) {
  const freeinit::sim::Recording& rec = recording(name, imu_rate);
  freeinit::FreeInitConfig cfg;
  cfg.extrinsics = rec.extrinsics;
  if (stride > 0) cfg.doppler.point_stride = stride;
  if (node_rate >= 0) cfg.joint.node_rate = node_rate;
  HeapStats before{}, after{};
  std::size_t used = 0;
  int iterations = 0;
  double t_div = 0, t_solve = 0, t_result = 0, t_map = 0;
  bool ok = true;
  double rate_hz = 0;
  for (auto _ : state) {
    before = g_heap;
    g_heap.peak = g_heap.live;
    {
      const freeinit::InitResult r = freeinit::FreeInit::run(cfg, rec.imu, rec.frames);
      after = g_heap;
      used = r.diag.points_used;
      iterations = r.diag.iterations;
      rate_hz = r.diag.update_rate_hz;
      t_div += r.diag.time_velocimeter;
      t_solve += r.diag.time_solver;
      t_result += r.diag.time_to_result;
      t_map += r.diag.time_map;
      ok = ok && r.state.status == freeinit::InitStatus::Ok;
      benchmark::DoNotOptimize(r.state.v_w.data());
    }
  }
  if (!ok) state.SkipWithError("initialization did not succeed");
  const double n = static_cast<double>(state.iterations());
  state.counters["stride"] = cfg.doppler.point_stride;  // 0: automatic (every point up to 3M/s)
  // Diagnostics: time_velocimeter is the estimator's time but the solves.
  state.counters["ms_filter"] = 1e3 * t_div / n;
  state.counters["ms_solver"] = 1e3 * t_solve / n;
  // Online latency: the frames are fed as they would arrive, so this is the time from the
  // frame that closes the window to the final result.
  state.counters["ms_to_result"] = 1e3 * t_result / n;
  state.counters["ms_map"] = 1e3 * t_map / n;  // the map, after the state
  state.counters["points_used"] = static_cast<double>(used);
  state.counters["smoother_iterations"] = iterations;  // all the window's smoothings
  state.counters["peak_heap_bytes"] = static_cast<double>(after.peak - before.live);
  state.counters["result_bytes"] = static_cast<double>(after.live - before.live);
  state.counters["allocs"] = static_cast<double>(after.allocs - before.allocs);
  // The velocimeter's output rate: state updates per second of data (the paper: > 10 kHz).
  state.counters["updates_per_s_of_data"] = rate_hz;
}

/// The filter's parameters in the forward-pass benchmarks: the defaults with the configuration's
/// Doppler noise, as the joint pipeline sets them.
freeinit::DopplerInertialFilterParams forwardPassParams(const freeinit::FreeInitConfig& cfg) {
  freeinit::DopplerInertialFilterParams fp;
  fp.doppler_sigma = cfg.doppler.doppler_sigma;
  return fp;
}

/// The last IMU sample of the window that starts at the recording's first (two samples after it
/// stay available to the filter's interpolation).
std::size_t lastNodeOfWindow(const freeinit::sim::Recording& rec,
                             const freeinit::FreeInitConfig& cfg) {
  const double t0 = rec.imu.front().t;
  std::size_t k_end = 0;
  while (k_end + 3 < rec.imu.size() && rec.imu[k_end].t - t0 < cfg.window.duration) ++k_end;
  return k_end;
}

/// The filter with the window's IMU samples, started at the true attitude and velocity.
void startAtTruth(freeinit::DopplerInertialFilter& filter, const freeinit::sim::Recording& rec,
                  std::size_t k_end) {
  for (std::size_t k = 0; k <= k_end + 2; ++k) filter.addImu(rec.imu[k]);
  const freeinit::sim::TruthState x = rec.truth(rec.imu.front().t);
  freeinit::FilterState x0;
  x0.R_wb = x.R_wb;
  x0.v_w = x.v_w;
  freeinit::DopplerInertialFilter::StartPrior prior;
  prior.cov_v_b = freeinit::Mat3::Identity() * 1e-4;
  filter.start(x0, prior);
}

/// Node k's returns as the joint pipeline's recorder lays them out for the filter (setReturns):
/// time from the node, position in the LiDAR frame, Doppler.
struct NodeArrays {
  std::vector<float> tau, x, y, z, doppler;
};

/// The returns of each node of the window up to node k_end, in range, as the filter's intervals
/// have them: time in [t_k - dt_before / 2, t_k + dt_after / 2) (the last node's up to t_k).
std::vector<NodeArrays> nodeArrays(const freeinit::sim::Recording& rec,
                                   const freeinit::FreeInitConfig& cfg, std::size_t k_end) {
  const double t0 = rec.imu.front().t;
  std::vector<NodeArrays> nodes(k_end + 1);
  for (const auto& f : rec.frames)
    for (const auto& p : f.points) {
      const double r = p.p_l.norm();
      if (r < cfg.doppler.min_range || r > cfg.doppler.max_range) continue;
      const double t = f.stamp + p.time_offset;
      if (t < t0 || t > rec.imu[k_end].t) continue;
      std::size_t k = 0;
      while (k < k_end && t >= rec.imu[k].t + 0.5 * (rec.imu[k + 1].t - rec.imu[k].t)) ++k;
      NodeArrays& n = nodes[k];
      n.tau.push_back(static_cast<float>(t - rec.imu[k].t));
      n.x.push_back(p.p_l.x());
      n.y.push_back(p.p_l.y());
      n.z.push_back(p.p_l.z());
      n.doppler.push_back(p.doppler);
    }
  return nodes;
}

/// One forward pass of the filter over the window from the truth (startAtTruth) to node k_end:
/// per node beginNode, the node's returns from `nodes` (none if null), update and predict.
/// Returns the returns given.
std::int64_t forwardPass(const freeinit::sim::Recording& rec,
                         const freeinit::DopplerInertialFilterParams& fp, std::size_t k_end,
                         const std::vector<NodeArrays>* nodes) {
  freeinit::DopplerInertialFilter filter(fp, rec.extrinsics);
  filter.reserveNodes(k_end + 1);
  startAtTruth(filter, rec, k_end);
  std::int64_t points = 0;
  for (std::size_t k = 0;; ++k) {
    const bool last = k == k_end;
    filter.beginNode(last);
    if (nodes != nullptr) {
      const NodeArrays& n = (*nodes)[k];
      filter.setReturns(
          {n.tau.size(), n.tau.data(), n.x.data(), n.y.data(), n.z.data(), n.doppler.data()});
      points += static_cast<std::int64_t>(n.tau.size());
    }
    filter.update();
    if (last) break;
    filter.predict();
  }
  benchmark::DoNotOptimize(filter.state(filter.nodes() - 1).v_w.data());
  return points;
}

/// items_per_second: returns per second; "points": returns per iteration.
void reportReturns(benchmark::State& state, std::int64_t points) {
  state.SetItemsProcessed(points);
  state.counters["points"] = static_cast<double>(points) / static_cast<double>(state.iterations());
}

/// The joint estimator's forward pass over the 0.5 s window alone (no start decision, no
/// smoothing), started at the truth: per node beginNode, the returns of its interval as the
/// arrays the pipeline's recorder lays out, made before the timed loop (setReturns: gate and
/// sums), update (solve, second gate with the coherence test, solve again), predict. The
/// filter's own per-return stage, without the layout, which BM_FreeInitRun counts.
/// `with_points` false: the nodes alone, so that the difference of the two is the per-point
/// stage. items_per_second: returns per second.
void BM_JointForwardPass(benchmark::State& state, const std::string& name, bool with_points) {
  const freeinit::sim::Recording& rec = recording(name);
  const freeinit::FreeInitConfig cfg;
  const freeinit::DopplerInertialFilterParams fp = forwardPassParams(cfg);
  const std::size_t k_end = lastNodeOfWindow(rec, cfg);
  const std::vector<NodeArrays> nodes = nodeArrays(rec, cfg, k_end);
  std::int64_t points = 0;
  for (auto _ : state) points += forwardPass(rec, fp, k_end, with_points ? &nodes : nullptr);
  reportReturns(state, points);
}

}  // namespace

BENCHMARK_CAPTURE(BM_JointForwardPass, dyna_05_every_point, std::string("dyna_05"), true)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_JointForwardPass, dyna_05_nodes_only, std::string("dyna_05"), false)
    ->Unit(benchmark::kMillisecond);

BENCHMARK_CAPTURE(BM_VelocimeterDoppler, dyna_05, std::string("dyna_05"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_VelocimeterDoppler, dyna_04, std::string("dyna_04"))
    ->Unit(benchmark::kMillisecond);

BENCHMARK_CAPTURE(BM_FreeInitRun, dyna_05_every_point, std::string("dyna_05"), 1, 0.0, -1.0)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FreeInitRun, dyna_01_every_point, std::string("dyna_01"), 1, 0.0, -1.0)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FreeInitRun, stat_01_every_point, std::string("stat_01"), 1, 0.0, -1.0)
    ->Unit(benchmark::kMillisecond);
// Decimation sweep on dyna_05 (the default's candidates).
BENCHMARK_CAPTURE(BM_FreeInitRun, dyna_05_stride2, std::string("dyna_05"), 2, 0.0, -1.0)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FreeInitRun, dyna_05_stride4, std::string("dyna_05"), 4, 0.0, -1.0)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FreeInitRun, dyna_05_stride8, std::string("dyna_05"), 8, 0.0, -1.0)
    ->Unit(benchmark::kMillisecond);
// IMU-rate sweep on dyna_05 (the preset's is 200 Hz) with a node per IMU sample: the window's
// nodes, 100 at 200 Hz, grow with the rate.
BENCHMARK_CAPTURE(BM_FreeInitRun, dyna_05_imu400_every_point, std::string("dyna_05"), 1, 400.0, 0.0)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FreeInitRun, dyna_05_imu1000_every_point, std::string("dyna_05"), 1, 1000.0,
                  0.0)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FreeInitRun, dyna_05_imu2000_every_point, std::string("dyna_05"), 1, 2000.0,
                  0.0)
    ->Unit(benchmark::kMillisecond);
// The same with nodes at 200 Hz ([joint] node_rate): every sample integrated, 100 nodes.
BENCHMARK_CAPTURE(BM_FreeInitRun, dyna_05_imu200_nodes200_every_point, std::string("dyna_05"), 1,
                  200.0, 200.0)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FreeInitRun, dyna_05_imu400_nodes200_every_point, std::string("dyna_05"), 1,
                  400.0, 200.0)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FreeInitRun, dyna_05_imu1000_nodes200_every_point, std::string("dyna_05"), 1,
                  1000.0, 200.0)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FreeInitRun, dyna_05_imu2000_nodes200_every_point, std::string("dyna_05"), 1,
                  2000.0, 200.0)
    ->Unit(benchmark::kMillisecond);

// Every preset at the default configuration: BM_FreeInitRun/<preset>_default.
int main(int argc, char** argv) {
  // Memory stays with the process between iterations, as in one that initializes again and again:
  // fresh pages would cost each iteration page faults (~8 us each on the project's VM) that
  // depend on where glibc happens to trim the heap, not on the estimator's work. Without this, a
  // benchmark that frees all it took (BM_JointForwardPass) met them or not depending on
  // the size of one per-node array (3.0 against 5.5 ms, 320 faults an iteration).
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
  for (const std::string& name : freeinit::sim::presetNames())
    benchmark::RegisterBenchmark(("BM_FreeInitRun/" + name + "_default").c_str(), BM_FreeInitRun,
                                 name, 0, 0.0, -1.0)
        ->Unit(benchmark::kMillisecond);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
