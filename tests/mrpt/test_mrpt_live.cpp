// The live path over loopback: freeinit-stream's app plays the committed sample to the online
// app and to the rawlog-grabber driver. What is recorded must be what was sent, object by object;
// the live initial state must equal the offline app's on the recording; faults must be counted
// and survived.
#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/doppler_lidar_imu_udp.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <freeinit/mrpt_plugins/rawlog_writer.h>
#include <freeinit/mrpt_plugins/stream_conversions.h>
#include <freeinit/net/stream_source.h>
#include <freeinit/net/udp_socket.h>
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <regex>
#include <sstream>
#include <thread>

#include "free_init_app.h"
#include "free_init_online_app.h"
#include "sim_app.h"
#include "stream_app.h"

using namespace freeinit;
using namespace freeinit::mrpt_plugins;
using namespace freeinit::app_support;
using namespace freeinit::apps;
namespace fs = std::filesystem;

namespace {
const std::string kSrc = FREEINIT_SOURCE_DIR;
const std::string kSample = kSrc + "/rawlogs/dyna_01.rawlog";

std::string outDir(const std::string& name) {
  const auto d = fs::temp_directory_path() / "freeinit_live_tests" / name;
  fs::remove_all(d);
  return d.string();
}

std::string readText(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// A rawlog's observations split by stream, in file order.
struct Streams {
  std::vector<mrpt::obs::CObservationIMU::Ptr> imu;
  std::vector<mrpt::obs::CObservationPointCloud::Ptr> clouds;
};

Streams readStreams(const std::string& rawlog) {
  std::vector<mrpt::obs::CObservation::Ptr> objs;
  for (const auto& r : readRawlog(rawlog)) objs.push_back(r.obs);
  Streams s;
  for (const auto& o : objs) {
    if (auto i = std::dynamic_pointer_cast<mrpt::obs::CObservationIMU>(o)) s.imu.push_back(i);
    if (auto c = std::dynamic_pointer_cast<mrpt::obs::CObservationPointCloud>(o))
      s.clouds.push_back(c);
  }
  return s;
}

// Exact equality of what the estimator reads: timestamps to the tick, every IMU value, every point
// field; the LiDAR pose to 1e-12 (it crosses the wire as a rotation matrix and is rebuilt).
void expectSameImu(const mrpt::obs::CObservationIMU& a, const mrpt::obs::CObservationIMU& b) {
  EXPECT_EQ(a.timestamp, b.timestamp);
  EXPECT_EQ(a.sensorLabel, b.sensorLabel);
  const ImuSample sa = imuFromObservation(a), sb = imuFromObservation(b);
  EXPECT_EQ(sa.gyro, sb.gyro);
  EXPECT_EQ(sa.accel, sb.accel);
}

void expectSameCloud(const mrpt::obs::CObservationPointCloud& a,
                     const mrpt::obs::CObservationPointCloud& b) {
  EXPECT_EQ(a.timestamp, b.timestamp);
  EXPECT_EQ(a.sensorLabel, b.sensorLabel);
  const LidarFrame fa = frameFromObservation(a), fb = frameFromObservation(b);
  ASSERT_EQ(fa.points.size(), fb.points.size());
  for (std::size_t i = 0; i < fa.points.size(); ++i) {
    ASSERT_EQ(fa.points[i].p_l, fb.points[i].p_l);
    ASSERT_EQ(fa.points[i].doppler, fb.points[i].doppler);
    ASSERT_EQ(fa.points[i].time_offset, fb.points[i].time_offset);
    ASSERT_EQ(fa.points[i].intensity, fb.points[i].intensity);
    ASSERT_EQ(fa.points[i].line, fb.points[i].line);
  }
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(a.sensorPose[k], b.sensorPose[k], 1e-12) << k;
}

// Every IMU sample and cloud sent arrived, exactly and in order.
void expectSameStreams(const Streams& got, const Streams& sent) {
  ASSERT_EQ(got.imu.size(), sent.imu.size());
  ASSERT_EQ(got.clouds.size(), sent.clouds.size());
  for (std::size_t i = 0; i < sent.imu.size(); ++i) expectSameImu(*got.imu[i], *sent.imu[i]);
  for (std::size_t i = 0; i < sent.clouds.size(); ++i)
    expectSameCloud(*got.clouds[i], *sent.clouds[i]);
}

// Runs the online app on a port of its own choosing while a StreamApp plays `sp` to it.
struct LiveRun {
  FreeInitOnlineApp app;
  StreamApp streamer;
  int exit_code = -1;
  std::string log;
};

void runLive(LiveRun& run, const std::string& out) {
  run.app.params.config_file = kSrc + "/ini/freeinit.ini";
  run.app.params.out_dir = out;
  run.app.params.source.port = 0;  // ephemeral: no clash with anything else on the machine
  run.app.params.wait_first = 20;
  run.app.params.idle_timeout = 3;
  std::thread sender;
  std::string stream_error;
  std::ostringstream stream_log;
  run.app.on_listening = [&](std::uint16_t port) {
    run.streamer.params.port = port;
    sender = std::thread([&] {
      try {
        run.streamer.run(stream_log);
      } catch (const std::exception& e) {
        stream_error = e.what();
      }
    });
  };
  std::ostringstream log;
  run.exit_code = run.app.run(log);
  if (sender.joinable()) sender.join();
  run.log = stream_log.str() + log.str();
  ASSERT_TRUE(stream_error.empty()) << stream_error;
}

// The offline app on a rawlog, writing to <out>/offline; its exit code.
int runOffline(const std::string& rawlog, const std::string& out) {
  FreeInitApp offline;
  offline.params.config_file = kSrc + "/ini/freeinit.ini";
  offline.params.rawlog = rawlog;
  offline.params.out_dir = out + "/offline";
  offline.params.progress = false;
  std::ostringstream log;
  const int code = offline.run(log);
  EXPECT_TRUE(fs::is_regular_file(out + "/offline/initial_state.ini")) << log.str();
  return code;
}

}  // namespace

TEST(LiveStream, RecordingMatchesWhatWasSentAndLiveStateEqualsOffline) {
  const std::string out = outDir("clean");
  LiveRun run;
  run.streamer.params.rawlog = kSample;
  run.streamer.params.speed = 4;
  runLive(run, out);
  ASSERT_EQ(run.exit_code, 0) << run.log;
  EXPECT_TRUE(run.app.ready_live) << run.log;
  EXPECT_GT(run.app.latency.total, 0);
  EXPECT_EQ(run.app.stats.anomalies(), 0u) << run.log;
  EXPECT_NE(readText(out + "/stream_stats.ini").find("anomalies_before_ready = 0\n"),
            std::string::npos);

  // Object by object: every IMU sample and cloud of the sample arrived, exactly.
  expectSameStreams(readStreams(run.app.record_path), readStreams(kSample));

  // The offline app on the recording: the same state, to the last digit (same observations in
  // the same order through the same handler).
  EXPECT_EQ(runOffline(run.app.record_path, out), 0);
  EXPECT_EQ(readText(out + "/initial_state.ini"), readText(out + "/offline/initial_state.ini"));
  EXPECT_FALSE(readText(out + "/initial_state.ini").empty());
  // And the files written when the stream ended.
  for (const char* f : {"trajectory_tum.txt", "static_map.ply", "velocimeter.csv"})
    EXPECT_EQ(readText(out + "/" + f), readText(out + "/offline/" + f)) << f;
}

TEST(LiveStream, NetworkFaultsAreCountedAndSurvived) {
  const std::string out = outDir("faults");
  LiveRun run;
  run.streamer.params.rawlog = kSample;
  run.streamer.params.speed = 4;
  run.streamer.params.faults.drop = 0.005;
  run.streamer.params.faults.duplicate = 0.02;
  run.streamer.params.faults.reorder = 0.02;
  run.streamer.params.faults.corrupt = 0.005;
  run.streamer.params.faults.seed = 7;
  run.streamer.params.garbage = 20;
  run.streamer.params.restart_at = 1.2;  // after the 0.5 s window: the state is still computed
  runLive(run, out);
  const auto& st = run.app.stats.receiver;
  const auto& injected = run.streamer.stats;
  EXPECT_GT(injected.dropped + injected.corrupted, 0u);
  EXPECT_EQ(st.sessions, 2u) << run.log;
  EXPECT_GE(st.malformed, injected.corrupted + injected.garbage) << run.log;
  EXPECT_GE(st.malformed + st.duplicates,
            injected.corrupted + injected.garbage + injected.duplicated)
      << run.log;
  EXPECT_GT(st.lost, 0u) << run.log;
  EXPECT_GT(st.out_of_order, 0u) << run.log;
  EXPECT_EQ(st.end_of_stream, 1u) << run.log;
  EXPECT_NE(run.log.find("Warning:"), std::string::npos) << "anomalies must be reported";
  // What was lost before the state was written is reported with it.
  ASSERT_TRUE(run.app.ready_live) << run.log;
  EXPECT_LE(run.app.stats_at_ready.anomalies(), run.app.stats.anomalies());
  EXPECT_NE(readText(out + "/stream_stats.ini")
                .find("anomalies_before_ready = " +
                      std::to_string(run.app.stats_at_ready.anomalies()) + "\n"),
            std::string::npos);
  EXPECT_NE(run.log.find("anomalies_before_ready = "), std::string::npos) << run.log;

  // Whatever arrived is exact, and nothing arrived twice or out of order.
  const Streams sent = readStreams(kSample);
  const Streams got = readStreams(run.app.record_path);
  std::map<mrpt::Clock::time_point, std::size_t> imu_at, cloud_at;
  for (std::size_t i = 0; i < sent.imu.size(); ++i) imu_at[sent.imu[i]->timestamp] = i;
  for (std::size_t i = 0; i < sent.clouds.size(); ++i) cloud_at[sent.clouds[i]->timestamp] = i;
  EXPECT_LT(got.imu.size(), sent.imu.size());
  for (std::size_t i = 0; i < got.imu.size(); ++i) {
    ASSERT_EQ(imu_at.count(got.imu[i]->timestamp), 1u);
    expectSameImu(*got.imu[i], *sent.imu[imu_at[got.imu[i]->timestamp]]);
    if (i > 0) {
      ASSERT_GT(got.imu[i]->timestamp, got.imu[i - 1]->timestamp);
    }
  }
  for (std::size_t i = 0; i < got.clouds.size(); ++i) {
    ASSERT_EQ(cloud_at.count(got.clouds[i]->timestamp), 1u);
    expectSameCloud(*got.clouds[i], *sent.clouds[cloud_at[got.clouds[i]->timestamp]]);
    if (i > 0) {
      ASSERT_GT(got.clouds[i]->timestamp, got.clouds[i - 1]->timestamp);
    }
  }
  // Every IMU sample or frame that did not arrive is accounted for by a counted anomaly.
  EXPECT_EQ(got.imu.size(), st.imu_samples);
  EXPECT_EQ(got.clouds.size(), st.frames);

  // The live result, whatever it is, is the offline result on the recording.
  EXPECT_EQ(runOffline(run.app.record_path, out), run.exit_code);
  EXPECT_EQ(readText(out + "/initial_state.ini"), readText(out + "/offline/initial_state.ini"));
}

// A simulator preset played live arrives as freeinit-sim would have written it, and initializes.
TEST(LiveStream, SimulatorPresetArrivesAsFreeinitSimWritesIt) {
  const std::string out = outDir("preset");
  SimApp sim;
  sim.params.preset = "stat_01";
  sim.params.duration = 0.8;
  sim.params.points_per_frame = 2000;
  sim.params.output = out + "/sim/stat_01.rawlog";
  std::ostringstream sim_log;
  sim.run(sim_log);

  LiveRun run;
  run.streamer.params.preset = "stat_01";
  run.streamer.params.duration = 0.8;
  run.streamer.params.points_per_frame = 2000;
  run.streamer.params.speed = 4;
  runLive(run, out);
  ASSERT_EQ(run.exit_code, 0) << run.log;
  EXPECT_EQ(run.app.stats.anomalies(), 0u) << run.log;
  expectSameStreams(readStreams(run.app.record_path), readStreams(sim.params.output));
  EXPECT_EQ(runOffline(run.app.record_path, out), 0);
  EXPECT_EQ(readText(out + "/initial_state.ini"), readText(out + "/offline/initial_state.ini"));
}

// Any StreamSource can feed the online app (a vendor SDK instead of UDP): here one that hands
// over the sample's messages directly.
class SampleSource : public net::StreamSource {
 public:
  /// Applied to every IMU and frame event; returning false leaves the event out.
  std::function<bool(net::StreamEvent&)> edit = [](net::StreamEvent&) { return true; };

  void start() override {
    net::StreamEvent e;
    e.kind = net::StreamEvent::Kind::SessionStart;
    events_.push_back(e);
    for (const auto& r : readRawlog(kSample)) {
      e.received = net::SteadyClock::now();
      if (auto imu = std::dynamic_pointer_cast<mrpt::obs::CObservationIMU>(r.obs)) {
        e.kind = net::StreamEvent::Kind::Imu;
        e.imu = imuMessage(*imu);
      } else if (auto pc = std::dynamic_pointer_cast<mrpt::obs::CObservationPointCloud>(r.obs)) {
        e.kind = net::StreamEvent::Kind::Frame;
        e.frame = frameMessage(*pc, extrinsicsFromPose(pc->sensorPose));
      }
      if (edit(e)) events_.push_back(e);
    }
    e.kind = net::StreamEvent::Kind::EndOfStream;
    events_.push_back(e);
  }
  void stop() override {}
  std::size_t poll(std::vector<net::StreamEvent>& out, double) override {
    const std::size_t n = events_.size();
    for (auto& e : events_) out.push_back(std::move(e));
    events_.clear();
    return n;
  }
  net::SourceStats stats() const override { return {}; }

 private:
  std::vector<net::StreamEvent> events_;
};

TEST(LiveStream, AnyStreamSourceFeedsTheOnlineApp) {
  const std::string out = outDir("source");
  FreeInitOnlineApp app;
  app.params.config_file = kSrc + "/ini/freeinit.ini";
  app.params.out_dir = out;
  app.source = std::make_unique<SampleSource>();
  std::ostringstream log;
  ASSERT_EQ(app.run(log), 0) << log.str();
  EXPECT_TRUE(app.ready_live);
  EXPECT_EQ(app.recorded, 316u);
  ASSERT_EQ(runOffline(kSample, out), 0);
  // In file order, the same observations: the same state as the offline app on the sample.
  EXPECT_EQ(readText(out + "/initial_state.ini"), readText(out + "/offline/initial_state.ini"));
}

// The offline validator's checks hold online too: bad input stops the run before any state is
// written (each of these inputs gives a state from the estimator if it reaches it). The earlier
// run's outputs stay as they were (only a complete new set replaces them); this run's recording
// and its statistics are kept beside them under a name with their time.
TEST(LiveStream, BadInputIsRefusedAsOffline) {
  struct Case {
    const char* what;
    std::function<bool(net::StreamEvent&)> edit;
    const char* error;
  };
  int imu_seen = 0;
  const std::vector<Case> cases = {
      {"accelerometer in g",
       [](net::StreamEvent& e) {
         if (e.kind == net::StreamEvent::Kind::Imu) e.imu.accel /= kGravity;
         return true;
       },
       "imu_accel_in_g = true"},
      {"ego-compensated Doppler",
       [](net::StreamEvent& e) {
         if (e.kind == net::StreamEvent::Kind::Frame)
           for (auto& p : e.frame.points) p.doppler = 0;
         return true;
       },
       "Doppler field is zero for every point"},
      {"IMU at an eighth of its rate (below min_imu_rate = 50 Hz)",
       [&imu_seen](net::StreamEvent& e) {
         return e.kind != net::StreamEvent::Kind::Imu || imu_seen++ % 8 == 0;
       },
       "below [input] min_imu_rate"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.what);
    const std::string out = outDir("bad_input");
    // Outputs of an earlier run in the same directory.
    const std::vector<std::string> stale = {"initial_state.ini", "static_map.ply",
                                            "trajectory_tum.txt", "stream_stats.ini"};
    fs::remove_all(out);
    fs::create_directories(out);
    for (const auto& f : stale) std::ofstream(out + "/" + f) << "earlier run\n";
    FreeInitOnlineApp app;
    app.params.config_file = kSrc + "/ini/freeinit.ini";
    app.params.out_dir = out;
    auto src = std::make_unique<SampleSource>();
    src->edit = c.edit;
    app.source = std::move(src);
    std::ostringstream log;
    try {
      app.run(log);
      ADD_FAILURE() << "accepted: " << log.str();
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.error), std::string::npos) << e.what();
    }
    EXPECT_FALSE(app.ready_live);
    for (const auto& f : stale)
      EXPECT_EQ(readText(out + "/" + f), "earlier run\n") << f << " of the earlier run changed";
    std::size_t kept = 0;
    for (const auto& e : fs::directory_iterator(out)) {
      const std::string n = e.path().filename().string();
      if (n.rfind("live.", 0) != 0) continue;
      ++kept;
      EXPECT_TRUE(
          std::regex_match(n, std::regex("live\\.[0-9]{8}-[0-9]{6}\\.(rawlog|stream_stats\\.ini)")))
          << n;
    }
    EXPECT_EQ(kept, 2u);
  }
}

// The rawlog-grabber driver as rawlog-grabber drives it: loadConfig, initialize, doProcess and
// getObservations at its process rate.
TEST(RawlogGrabberDriver, EmitsExactlyWhatWasSent) {
  std::uint16_t port = 0;
  {
    net::UdpSocket probe;  // a free port for the INI
    probe.bind("127.0.0.1", 0);
    port = probe.localPort();
  }
  mrpt::config::CConfigFileMemory cfg;
  cfg.setContent("[LIVE]\ndriver = CDopplerLidarImuUdp\nprocess_rate = 200\nport = " +
                 std::to_string(port) + "\nstats_period_s = 0\n");
  CDopplerLidarImuUdp sensor;
  sensor.loadConfig(cfg, "LIVE");
  sensor.initialize();

  StreamApp streamer;
  streamer.params.rawlog = kSample;
  streamer.params.speed = 4;
  streamer.params.port = port;
  std::ostringstream slog;
  streamer.run(slog);

  std::vector<mrpt::obs::CObservation::Ptr> objs;
  // Until the end-of-stream marker had been received before a doProcess (the source queues a
  // datagram's items with its statistics, so nothing received is left behind), or a deadline
  // generous for a loaded machine.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < deadline) {
    const bool ended = sensor.stats().receiver.end_of_stream > 0;
    sensor.doProcess();
    for (const auto& [t, o] : sensor.getObservations())
      objs.push_back(std::dynamic_pointer_cast<mrpt::obs::CObservation>(o));
    if (ended) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_GT(sensor.stats().receiver.end_of_stream, 0u) << "no end of stream within 20 s";
  Streams got;
  for (const auto& o : objs) {
    if (auto m = std::dynamic_pointer_cast<mrpt::obs::CObservationIMU>(o)) got.imu.push_back(m);
    if (auto c = std::dynamic_pointer_cast<mrpt::obs::CObservationPointCloud>(o))
      got.clouds.push_back(c);
  }
  EXPECT_EQ(sensor.stats().anomalies(), 0u);
  expectSameStreams(got, readStreams(kSample));
}

TEST(RawlogGrabberDriver, BadConfigurationNamesTheKey) {
  mrpt::config::CConfigFileMemory cfg;
  cfg.setContent("[LIVE]\ndriver = CDopplerLidarImuUdp\nprocess_rate = 100\nport = 70000\n");
  CDopplerLidarImuUdp sensor;
  try {
    sensor.loadConfig(cfg, "LIVE");
    FAIL() << "accepted port 70000";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("port"), std::string::npos) << e.what();
  }
}

// freeinit-stream checks a rawlog as the offline app does; an IMU in g is refused unless declared,
// and then sent in m/s^2.
TEST(StreamApp, RawlogInGIsRefusedOrConverted) {
  const std::string out = outDir("stream_in_g");
  const std::string in_g = out + "/in_g.rawlog";
  {
    RawlogWriter writer(in_g);
    for (const auto& r : readRawlog(kSample)) {
      if (auto imu = std::dynamic_pointer_cast<mrpt::obs::CObservationIMU>(r.obs)) {
        ImuSample sample = imuFromObservation(*imu);
        sample.accel /= kGravity;
        auto o = imuToObservation(sample, imu->sensorLabel);
        o->timestamp = imu->timestamp;
        o->sensorPose = imu->sensorPose;
        writer.write(*o);
      } else {
        writer.write(*r.obs);
      }
    }
    writer.commit();
  }
  StreamApp refused;
  refused.params.rawlog = in_g;
  refused.params.speed = 0;
  std::ostringstream log;
  try {
    refused.run(log);
    FAIL() << "streamed accelerations in g as m/s^2";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("imu_accel_in_g"), std::string::npos) << e.what();
  }

  net::UdpSourceParams sp;
  sp.port = 0;
  sp.max_queued_imu = 100000;
  sp.max_queued_frames = 1000;
  net::UdpStreamSource source(sp);
  source.start();
  StreamApp converted;
  converted.params.rawlog = in_g;
  converted.params.imu_accel_in_g = true;
  converted.params.speed = 0;
  converted.params.port = source.port();
  converted.run(log);
  std::vector<net::StreamEvent> ev;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (source.stats().receiver.end_of_stream == 0 && std::chrono::steady_clock::now() < deadline)
    source.poll(ev, 0.05);
  source.poll(ev, 0.0);
  const Streams sent = readStreams(kSample);
  std::size_t i = 0;
  for (const auto& e : ev) {
    if (e.kind != net::StreamEvent::Kind::Imu) continue;
    ASSERT_LT(i, sent.imu.size());
    // x / g * g is x to within an ulp or two.
    const Vec3 want = imuFromObservation(*sent.imu[i++]).accel;
    EXPECT_LT((e.imu.accel - want).norm(), 1e-12 * want.norm());
  }
  EXPECT_EQ(i, sent.imu.size());
}

// The recorder's writer: a final flush that fails (here: the temporary is /dev/full, which takes
// the open but no byte) is an error, and nothing is renamed onto the rawlog's path.
TEST(RawlogWriter, AFailedFinalFlushIsAnErrorNotARename) {
  const std::string out = outDir("writer_full");
  fs::create_directories(out);
  const std::string path = out + "/full.rawlog";
  fs::create_symlink("/dev/full", path + ".tmp");
  RawlogWriter writer(path);
  ImuSample s;
  s.t = 1.0;
  writer.write(s);  // small: it stays in zlib's buffer until the close
  EXPECT_THROW(writer.commit(), std::runtime_error);
  EXPECT_FALSE(fs::exists(fs::symlink_status(path)));
}

TEST(StreamConversions, NanosecondsAndClockTicksAgree) {
  const auto t = fromUnix(1700000000.1234567);
  EXPECT_EQ(fromUnixNs(toUnixNs(t)), t);
  EXPECT_NEAR(1e-9 * static_cast<double>(toUnixNs(t)), toUnix(t), 1e-6);
}

TEST(StreamConversions, OutOfRangeStampsThrowAndRoundingCannotOverflow) {
  EXPECT_THROW(toUnixNs(INVALID_TIMESTAMP), std::invalid_argument);
  EXPECT_THROW(toUnixNs(fromUnix(-1.0)), std::invalid_argument);  // before 1970
  EXPECT_EQ(toUnixNs(fromUnixNs(0)), 0);
  // The last whole tick below 2^62 ns converts; the next one does not.
  constexpr std::int64_t kLast = (freeinit::net::kMaxStampNs - 1) / 100 * 100;
  EXPECT_EQ(toUnixNs(fromUnixNs(kLast)), kLast);
  EXPECT_THROW(toUnixNs(fromUnixNs(kLast + 100)), std::invalid_argument);
  // Nearest tick, halves away from zero, up to the int64 limits (ns +/- 50 would overflow there).
  const auto ticks = [](std::int64_t ns) { return fromUnixNs(ns).time_since_epoch().count(); };
  EXPECT_EQ(ticks(149) - ticks(0), 1);
  EXPECT_EQ(ticks(150) - ticks(0), 2);
  EXPECT_EQ(ticks(-149) - ticks(0), -1);
  EXPECT_EQ(ticks(-150) - ticks(0), -2);
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();  // ...807
  constexpr std::int64_t kMin = std::numeric_limits<std::int64_t>::min();  // ...808
  EXPECT_EQ(ticks(kMax) - ticks(0), kMax / 100);                           // remainder 7: down
  EXPECT_EQ(ticks(kMin) - ticks(0), kMin / 100);       // remainder -8: towards zero
  EXPECT_EQ(ticks(kMax - 57) - ticks(0), kMax / 100);  // remainder 50: away from zero
}
