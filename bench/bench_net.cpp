// The live stream's cost per LiDAR frame of 60,000 points (an Aeries II-like frame at 10 Hz):
// encoding into datagrams, decoding + reassembly, and the whole loopback path (send, kernel,
// receiving thread, queue). Each must take far less than the 100 ms between frames.
#include <benchmark/benchmark.h>
#include <freeinit/net/stream_receiver.h>
#include <freeinit/net/stream_sender.h>
#include <freeinit/net/stream_source.h>

#include <random>

using namespace freeinit;
using namespace freeinit::net;

namespace {

constexpr std::size_t kPoints = 60000;

FrameMessage makeFrame(std::int64_t stamp_ns) {
  FrameMessage f;
  f.stamp_ns = stamp_ns;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-50.f, 50.f);
  f.points.resize(kPoints);
  for (std::size_t i = 0; i < kPoints; ++i) {
    auto& p = f.points[i];
    p.p_l = Eigen::Vector3f(u(rng), u(rng), u(rng));
    p.doppler = u(rng) / 10;
    p.time_offset = 0.1f * static_cast<float>(i) / kPoints;
    p.line = static_cast<std::uint16_t>(i % 64);
  }
  return f;
}

void BM_EncodeFrame(benchmark::State& state) {
  const FrameMessage f = makeFrame(0);
  std::uint64_t seq = 0;
  for (auto _ : state) {
    auto d = encodeFrame(f, 1, seq, static_cast<std::size_t>(state.range(0)));
    benchmark::DoNotOptimize(d.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * kPoints));
}
BENCHMARK(BM_EncodeFrame)->Arg(1472)->Arg(8192)->Unit(benchmark::kMillisecond);

void BM_DecodeAndReassembleFrame(benchmark::State& state) {
  const FrameMessage f = makeFrame(0);
  std::uint64_t seq = 0;
  const auto datagrams = encodeFrame(f, 1, seq, static_cast<std::size_t>(state.range(0)));
  std::vector<StreamEvent> out;
  for (auto _ : state) {
    StreamReceiver r;
    out.clear();
    const auto now = SteadyClock::now();
    for (const auto& d : datagrams) r.push(d.data(), d.size(), now, out);
    if (out.size() != 2) state.SkipWithError("frame not reassembled");
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * kPoints));
}
BENCHMARK(BM_DecodeAndReassembleFrame)->Arg(1472)->Arg(8192)->Unit(benchmark::kMillisecond);

// Sender -> loopback UDP -> receiving thread -> queue -> consumer, one frame per iteration.
void BM_LoopbackFrame(benchmark::State& state) {
  UdpSourceParams sp;
  sp.port = 0;
  UdpStreamSource source(sp);
  source.start();
  StreamSender sender("127.0.0.1", source.port(), 8192);
  std::int64_t stamp = 0;
  std::vector<StreamEvent> out;
  FrameMessage f = makeFrame(0);
  for (auto _ : state) {
    f.stamp_ns = (stamp += 100'000'000);
    sender.sendFrame(f);
    bool got = false;
    for (int i = 0; i < 1000 && !got; ++i) {
      out.clear();
      source.poll(out, 0.01);
      for (const auto& e : out) got |= e.kind == StreamEvent::Kind::Frame;
    }
    if (!got) state.SkipWithError("frame lost on loopback");
  }
  state.counters["anomalies"] = static_cast<double>(source.stats().anomalies());
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * kPoints));
}
BENCHMARK(BM_LoopbackFrame)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
