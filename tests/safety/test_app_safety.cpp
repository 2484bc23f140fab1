// The apps as a user runs them, as processes: stopped by SIGINT / SIGTERM, two runs on one
// output, a full disk, live recordings across runs, a recording cut short, and the messages of
// bad inputs. Each case asserts the exit status, the message and what is left on disk.
#include <fcntl.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <freeinit/mrpt_plugins/rawlog_writer.h>
#include <gtest/gtest.h>
#include <mrpt/obs/CObservationIMU.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include "app_process.h"

namespace {

using namespace app_test;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

const std::string kSrc = FREEINIT_SOURCE_DIR;
const std::string kIni = kSrc + "/ini/freeinit.ini";
const std::string kSample = kSrc + "/rawlogs/dyna_01.rawlog";

/// What an earlier run of freeinit left: a complete set.
void earlierFreeinitRun(const fs::path& out) {
  Process p({FREEINIT_APP, kIni, kSample, "-q", "--out", out.string()}, out.parent_path(),
            "earlier");
  ASSERT_EQ(exitCode(p.wait()), 0) << p.err();
  ASSERT_TRUE(fs::exists(out / "errors_wrt_gt.ini"));
}

/// Runs `argv` and stops it with `sig` while it works; the run must end by that signal with one
/// line, leaving `expected` (what is not ours) and nothing else.
void expectStoppedCleanly(const std::vector<std::string>& argv, const fs::path& dir,
                          const fs::path& staging, int sig, const std::set<std::string>& expected,
                          const std::string& program) {
  for (int attempt = 0; attempt < 5; ++attempt) {
    Process p(argv, dir, "stopped");
    if (!interruptWhileStaged(p, staging, sig)) {
      p.wait();
      continue;  // it finished first: again
    }
    const int st = p.wait();
    EXPECT_TRUE(killedBy(st, sig)) << "status " << st << "\n" << p.err();
    EXPECT_EQ(p.err(), program + ": stopped by " + (sig == SIGINT ? "SIGINT" : "SIGTERM") +
                           "; no output of this run was written\n");
    std::set<std::string> left = listing(dir);
    left.erase("stopped.out");
    left.erase("stopped.err");
    EXPECT_EQ(left, expected);
    return;
  }
  FAIL() << "the run always ended before it could be stopped";
}

// Ctrl-C while freeinit works: nothing of this run is left, no temporary file; the earlier run's
// outputs stay as they were (only a complete new set replaces them), and so does the user's file.
TEST(StopSignals, FreeinitLeavesNoOutputOfItsOwnAndTheEarlierSetAsItWas) {
  for (const int sig : {SIGINT, SIGTERM}) {
    const fs::path d = freshDir(sig == SIGINT ? "freeinit_sigint" : "freeinit_sigterm");
    const fs::path out = d / "out";
    earlierFreeinitRun(out);
    std::ofstream(out / "notes.txt") << "mine\n";
    const std::string state = readText(out / "initial_state.ini");
    expectStoppedCleanly({FREEINIT_APP, kIni, kSample, "-q", "--check-all", "--out", out.string()},
                         d, out / ".freeinit.staging", sig, listing(d), "freeinit");
    EXPECT_EQ(readText(out / "initial_state.ini"), state);
  }
}

TEST(StopSignals, SimulatorLeavesNoFile) {
  const fs::path d = freshDir("sim_sigterm");
  expectStoppedCleanly({FREEINIT_SIM_APP, "-p", "dyna_05", "-d", "3", "-n", "20000", "-o",
                        (d / "x.rawlog").string()},
                       d, d / ".x.freeinit.staging", SIGTERM, {}, "freeinit-sim");
}

TEST(StopSignals, IcpSlamLeavesNoFile) {
  const fs::path d = freshDir("icp_sigint");
  expectStoppedCleanly({FREEINIT_ICP_SLAM_APP, kSrc + "/ini/icp_slam.ini", kIni, kSample, "--out",
                        (d / "out").string(), "--export", (d / "export").string()},
                       d, d / "out" / ".freeinit.staging", SIGINT, {}, "freeinit-icp-slam");
}

TEST(StopSignals, EvalRawlogLeavesNoFile) {
  const fs::path d = freshDir("eval_sigint");
  expectStoppedCleanly({FREEINIT_EVAL_RAWLOG_APP, kIni, kSample, kSrc + "/rawlogs/stat_01.rawlog",
                        "--csv", (d / "eval.csv").string(), "--md", (d / "eval.md").string()},
                       d, d / ".eval.csv.freeinit.staging", SIGINT, {}, "freeinit-eval-rawlog");
}

// Two runs on one folder: the second is refused at once with one line naming the folder and the
// holder; the first then completes its set alone.
TEST(OutputLock, ASecondRunOnTheSameOutputIsRefused) {
  const fs::path d = freshDir("lock");
  const fs::path out = d / "out";
  for (int attempt = 0;; ++attempt) {
    ASSERT_LT(attempt, 5) << "the first run always ended before the second started";
    Process first({FREEINIT_APP, kIni, kSample, "-q", "--out", out.string()}, d, "first");
    ASSERT_TRUE(
        waitUntil([&] { return fs::exists(out / ".freeinit.staging") || !first.running(); }));
    first.signal(SIGSTOP);
    if (!fs::exists(out / ".freeinit.staging")) {
      first.signal(SIGCONT);
      first.wait();
      continue;
    }
    Process second(
        {FREEINIT_APP, kIni, kSrc + "/rawlogs/stat_01.rawlog", "-q", "--out", out.string()}, d,
        "second");
    const int st = second.wait();
    first.signal(SIGCONT);
    EXPECT_EQ(exitCode(st), 1);
    const std::string err = second.err();
    EXPECT_EQ(lineCount(err), 1u) << err;
    EXPECT_CONTAINS(err, "freeinit: error: " + out.string() + ": in use by another run (pid " +
                             std::to_string(first.pid()) + ": freeinit " + kIni + " " + kSample);
    EXPECT_EQ(exitCode(first.wait()), 0) << first.err();
    break;
  }
  // The set is the first run's, whole.
  for (const char* f : {"initial_state.ini", "errors_wrt_gt.ini", "static_map.ply", "velocity.png"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  EXPECT_FALSE(fs::exists(out / ".freeinit.lock"));
  EXPECT_FALSE(fs::exists(out / ".freeinit.staging"));
}

// A full disk: one line saying "no space left" and naming the file; nothing that looks like a
// result is left (the folder the run created goes too). (freeinit-sim refuses a recording that
// will not fit before it writes: test_user_data.cpp.)
TEST(FullDisk, NoSpaceLeftNamesTheFileAndLeavesNothing) {
  const fs::path d = freshDir("full_disk");
  const fs::path mnt = d / "mnt";
  const std::string script = std::string(FREEINIT_APP) + " -q " + kIni + " " + kSample + " --out " +
                             mnt.string() + "/out > " + (d / "freeinit.out").string() + " 2> " +
                             (d / "freeinit.err").string() + "; echo $? > " +
                             (d / "freeinit.rc").string() + "; ls -A " + mnt.string() + " > " +
                             (d / "freeinit.left").string();
  if (!withSmallDisk(mnt, "400k", script, d / "unshare.log"))
    GTEST_SKIP() << "cannot mount a tmpfs here (not root?)";
  EXPECT_EQ(readText(d / "freeinit.rc"), "1\n") << readText(d / "unshare.log");
  const std::string err = readText(d / "freeinit.err");
  EXPECT_EQ(lineCount(err), 1u) << err;
  EXPECT_TRUE(std::regex_search(
      err, std::regex("^freeinit: error: " + mnt.string() +
                      "/out/[a-z_.]+: cannot be written: no space left "
                      "on the device \\(" +
                      mnt.string() + "/out is full\\); nothing of this run is left in " +
                      mnt.string() + "/out\n$")))
      << err;
  EXPECT_EQ(readText(d / "freeinit.left"), "");
}

// --- live recordings ---

std::size_t readableRecords(const std::string& rawlog) {
  return freeinit::mrpt_plugins::readRawlog(rawlog).size();
}

// Stopping freeinit-online with Ctrl-C or SIGTERM (the normal way to stop a live tool) while the
// stream runs: the recording is closed as a readable rawlog with its statistics; the earlier
// run's recording is kept under another name, never deleted.
TEST(LiveRecordings, StoppedWhileStreamingTheRecordingIsReadableAndTheEarlierOneKept) {
  for (const int sig : {SIGINT, SIGTERM}) {
    const fs::path d = freshDir(sig == SIGINT ? "live_sigint" : "live_sigterm");
    const fs::path out = d / "live";
    fs::create_directories(out);
    fs::copy_file(kSample, out / "live.rawlog");  // an earlier run's recording
    std::ofstream(out / "stream_stats.ini") << "[stream]\nearlier = 1\n";
    std::ofstream(out / "initial_state.ini") << "[initial_state]\nstatus = ok\n";
    Process online({FREEINIT_ONLINE_APP, kIni, "-o", out.string(), "-p", "0", "-i", "30"}, d,
                   "online");
    const int port = listeningPort(online);
    ASSERT_GT(port, 0) << online.err();
    Process stream({FREEINIT_STREAM_APP, "-i", kSample, "-p", std::to_string(port), "-x", "0.5"}, d,
                   "stream");
    // The window closed: this run's state and configuration replaced the earlier run's outputs,
    // its recording renamed.
    ASSERT_TRUE(waitUntil([&] { return fs::exists(out / "effective_config.ini"); }));
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    online.signal(sig);
    const int st = online.wait();
    stream.wait();
    EXPECT_TRUE(exitCode(st) == 0 || exitCode(st) == 3) << st << online.err();
    EXPECT_CONTAINS(online.out(),
                    std::string("Stopped by ") + (sig == SIGINT ? "SIGINT" : "SIGTERM"));
    EXPECT_GT(readableRecords((out / "live.rawlog").string()), 0u);
    EXPECT_CONTAINS(readText(out / "stream_stats.ini"),
                    std::string("stopped_by          = ") + (sig == SIGINT ? "SIGINT" : "SIGTERM"));
    std::size_t kept = 0;
    for (const auto& e : fs::directory_iterator(out)) {
      const std::string n = e.path().filename().string();
      if (std::regex_match(n, std::regex("live\\.[0-9]{8}-[0-9]{6}\\.rawlog"))) {
        ++kept;
        EXPECT_EQ(fs::file_size(e.path()), fs::file_size(kSample));
        const std::string stats = n.substr(0, n.size() - 7) + ".stream_stats.ini";
        EXPECT_EQ(readText(out / stats), "[stream]\nearlier = 1\n");
      }
      EXPECT_EQ(n.find(".tmp"), std::string::npos) << n;
    }
    EXPECT_EQ(kept, 1u);
    EXPECT_FALSE(fs::exists(out / ".freeinit.staging"));
    EXPECT_FALSE(fs::exists(out / ".freeinit.lock"));
  }
}

// A stop signal that comes after the stream ended, while the outputs are written: it asks for
// what is under way, so the run finishes its outputs, exit code the run's.
TEST(LiveRecordings, ASignalWhileTheOutputsAreWrittenCostsNothing) {
  const fs::path d = freshDir("live_late_signal");
  const fs::path out = d / "live";
  for (int attempt = 0;; ++attempt) {
    ASSERT_LT(attempt, 5) << "the outputs were always written before the signal";
    Process online({FREEINIT_ONLINE_APP, kIni, "-o", out.string(), "-p", "0", "-i", "30"}, d,
                   "online");
    const int port = listeningPort(online);
    ASSERT_GT(port, 0) << online.err();
    Process stream({FREEINIT_STREAM_APP, "-i", kSample, "-p", std::to_string(port), "-x", "2"}, d,
                   "stream");
    // The statistics are staged once the stream has ended, before the other outputs.
    const fs::path stats = out / ".freeinit.staging" / "stream_stats.ini";
    ASSERT_TRUE(waitUntil([&] { return fs::exists(stats) || !online.running(); }));
    online.signal(SIGSTOP);
    const bool in_time = fs::exists(stats);
    if (in_time) online.signal(SIGTERM);
    online.signal(SIGCONT);
    const int st = online.wait();
    stream.wait();
    if (!in_time) continue;
    EXPECT_EQ(exitCode(st), 0) << st << online.err();
    EXPECT_EQ(online.err(), "");
    for (const char* f :
         {"initial_state.ini", "static_map.ply", "velocity.png", "live.rawlog", "stream_stats.ini"})
      EXPECT_TRUE(fs::exists(out / f)) << f;
    EXPECT_EQ(readText(out / "stream_stats.ini").find("stopped_by"), std::string::npos);
    break;
  }
}

// Re-running freeinit-online when no data ever arrives leaves the earlier recording as it was;
// into a new folder, it leaves no folder.
TEST(LiveRecordings, NoDataTheEarlierRecordingIsLeftAsItWas) {
  const fs::path d = freshDir("live_no_data");
  const fs::path out = d / "live";
  fs::create_directories(out);
  fs::copy_file(kSample, out / "live.rawlog");
  Process online({FREEINIT_ONLINE_APP, kIni, "-o", out.string(), "-p", "0", "-w", "0.3"}, d,
                 "online");
  EXPECT_EQ(exitCode(online.wait()), 1);
  EXPECT_EQ(online.err(),
            "freeinit-online: error: live stream: no data received within 0.3 s; nothing of this "
            "run is left in " +
                out.string() + ", the earlier outputs there are as they were\n");
  EXPECT_EQ(listing(out), (std::set<std::string>{"live.rawlog"}));
  EXPECT_EQ(fs::file_size(out / "live.rawlog"), fs::file_size(kSample));

  Process fresh({FREEINIT_ONLINE_APP, kIni, "-o", (d / "new").string(), "-p", "0", "-w", "0.3"}, d,
                "fresh");
  EXPECT_EQ(exitCode(fresh.wait()), 1);
  EXPECT_EQ(fresh.err(),
            "freeinit-online: error: live stream: no data received within 0.3 s; nothing of this "
            "run is left in " +
                (d / "new").string() + "\n");
  EXPECT_FALSE(fs::exists(d / "new"));
}

// A run killed outright (SIGKILL, a power loss) leaves its recording in the staging folder: the
// next run keeps it, says so, and it reads up to its last whole record with --salvage.
TEST(LiveRecordings, ARecordingOfARunThatDiedIsKeptByTheNextRun) {
  const fs::path d = freshDir("live_killed");
  const fs::path out = d / "live";
  {
    Process online({FREEINIT_ONLINE_APP, kIni, "-o", out.string(), "-p", "0", "-i", "30"}, d,
                   "online");
    const int port = listeningPort(online);
    ASSERT_GT(port, 0);
    Process stream({FREEINIT_STREAM_APP, "-i", kSample, "-p", std::to_string(port), "-x", "0.5"}, d,
                   "stream");
    const fs::path staged = out / ".freeinit.staging" / "live.rawlog.tmp";
    ASSERT_TRUE(waitUntil([&] { return fs::exists(staged) && fs::file_size(staged) > 200000; }));
    online.signal(SIGKILL);
    online.wait();
    stream.wait();
  }
  Process next({FREEINIT_ONLINE_APP, kIni, "-o", out.string(), "-p", "0", "-w", "0.2"}, d, "next");
  next.wait();
  std::smatch m;
  const std::string log = next.out();
  ASSERT_TRUE(std::regex_search(
      log, m,
      std::regex("Kept the recording of an interrupted run as (\\S+live\\.[0-9-]+\\.rawlog)")))
      << log;
  const std::string kept = m[1];
  EXPECT_TRUE(fs::exists(kept));
  Process strict({FREEINIT_APP, kIni, kept, "-q", "--out", (d / "strict").string()}, d, "strict");
  EXPECT_EQ(exitCode(strict.wait()), 1);
  Process salvage({FREEINIT_APP, kIni, kept, "-q", "--salvage", "--out", (d / "salvage").string()},
                  d, "salvage");
  const int st = salvage.wait();
  EXPECT_TRUE(exitCode(st) == 0 || exitCode(st) == 1) << salvage.err();
  EXPECT_CONTAINS(salvage.out(), "Warning: " + kept + ": read up to record ");
}

// A rawlog cut short (power loss while recording): the strict reader refuses what the cut
// reaches, naming the record; --salvage reads up to the last whole record, says where it stopped,
// and the windows the cut ends close as at the end of a file.
TEST(Salvage, ACutRecordingIsReadUpToItsLastWholeRecord) {
  const fs::path d = freshDir("salvage");
  const fs::path cut = d / "cut.rawlog";
  fs::copy_file(kSample, cut);
  fs::resize_file(cut, fs::file_size(cut) * 6 / 10);
  Process strict(
      {FREEINIT_APP, kIni, cut.string(), "-q", "--every", "0.3", "--out", (d / "strict").string()},
      d, "strict");
  EXPECT_EQ(exitCode(strict.wait()), 3);
  EXPECT_TRUE(std::regex_search(
      strict.out(), std::regex("Start 2 at 0\\.600 s: input_error \\(\\S+cut\\.rawlog: record "
                               "[0-9]+: the file ends inside this record \\(truncated file")))
      << strict.out();
  Process salvage({FREEINIT_APP, kIni, cut.string(), "-q", "--every", "0.3", "--salvage", "--out",
                   (d / "salvaged").string()},
                  d, "salvage");
  EXPECT_EQ(exitCode(salvage.wait()), 0) << salvage.err();
  EXPECT_TRUE(std::regex_search(
      salvage.out(),
      std::regex("Warning: \\S+cut\\.rawlog: read up to record ([0-9]+), the last whole one; "
                 "record [0-9]+ \\(byte [0-9]+ of the decompressed stream, about byte [0-9]+ of "
                 "the file\\): the file ends inside this record \\(truncated file")))
      << salvage.out();
  EXPECT_CONTAINS(salvage.out(), "Start 2 at 0.600 s: not_enough_data (the recording ends");
  EXPECT_TRUE(fs::exists(d / "salvaged" / "start_0000.300" / "initial_state.ini"));
}

// --- messages: one line naming the file, the record and the likely cause ---

struct Outcome {
  int code;
  std::string out, err;
};

Outcome runFreeinit(const fs::path& d, const std::string& ini, const std::string& rawlog) {
  Process p({FREEINIT_APP, ini, rawlog, "-q", "--out", (d / "out").string()}, d, "run");
  const int st = p.wait();
  EXPECT_FALSE(fs::exists(d / "out"));
  return {exitCode(st), p.out(), p.err()};
}

TEST(Messages, AFolderGivenAsTheRawlog) {
  const fs::path d = freshDir("msg_folder");
  const auto r = runFreeinit(d, kIni, d.string());
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err, "freeinit: error: " + d.string() + ": is a folder, not a rawlog file\n");
}

TEST(Messages, SwappedRawlogAndIniSaysWhatTheFileIsWithoutBinary) {
  const fs::path d = freshDir("msg_swapped");
  const auto r = runFreeinit(d, kSample, kIni);
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lineCount(r.err), 1u) << r.err;
  EXPECT_CONTAINS(r.err, "freeinit: error: " + kSample + ":1: binary data");
  EXPECT_CONTAINS(r.err, "not an INI text file");
  for (const char c : r.err) EXPECT_TRUE(c == '\n' || (c >= 32 && c < 127)) << int(c);
  EXPECT_EQ(r.err.find("backtrace"), std::string::npos);
}

// What an MRPT tool without the plugin makes of a rawlog with Doppler clouds: the records before
// the first cloud, or none at all. The messages say so and name the flag.
TEST(Messages, ARawlogEmptiedByAStockToolHintsAtThePlugin) {
  const fs::path d = freshDir("msg_stock");
  const fs::path empty = d / "empty.rawlog";
  {
    // rawlog-edit without -p, keeping the clouds only: an empty gzip stream.
    freeinit::mrpt_plugins::RawlogWriter w(empty.string());
    w.commit();
  }
  auto r = runFreeinit(d, kIni, empty.string());
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lineCount(r.err), 1u) << r.err;
  EXPECT_CONTAINS(r.err, empty.string() + ": no rawlog record in the file");
  EXPECT_CONTAINS(r.err, "-p libfreeinit_mrpt_plugins.so");

  const fs::path imu_only = d / "imu_only.rawlog";
  {
    freeinit::mrpt_plugins::RawlogWriter w(imu_only.string());
    for (int i = 0; i < 301; ++i) {
      freeinit::ImuSample s;
      s.t = 1700000000.0 + 0.005 * i;
      s.accel = freeinit::Vec3(0, 0, 9.81);
      w.write(s);
    }
    w.commit();
  }
  r = runFreeinit(d, kIni, imu_only.string());
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lineCount(r.err), 1u) << r.err;
  EXPECT_CONTAINS(r.err, imu_only.string() +
                             ": no CObservationPointCloud with sensorLabel 'LIDAR' ([input] "
                             "lidar_label); the input holds only 301 IMU samples 'IMU'");
  EXPECT_CONTAINS(r.err, "-p libfreeinit_mrpt_plugins.so");
}

// Stamps 200 ns apart print differently: one IMU stamp of the sample moved just before the
// previous one, inside the window.
TEST(Messages, StampsHaveTheDigitsToDiffer) {
  const fs::path d = freshDir("msg_stamps");
  const fs::path f = d / "back.rawlog";
  {
    auto records = freeinit::mrpt_plugins::readRawlog(kSample);
    freeinit::mrpt_plugins::RawlogWriter w(f.string());
    std::optional<mrpt::Clock::time_point> previous_imu;
    int imu = 0;
    for (auto& r : records) {
      if (IS_CLASS(*r.obs, mrpt::obs::CObservationIMU)) {
        if (++imu == 40) r.obs->timestamp = *previous_imu - mrpt::Clock::duration(2);  // 200 ns
        previous_imu = r.obs->timestamp;
      }
      w.write(*r.obs);
    }
    w.commit();
  }
  const auto r = runFreeinit(d, kIni, f.string());
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lineCount(r.err), 1u) << r.err;
  EXPECT_TRUE(std::regex_search(
      r.err,
      std::regex("back\\.rawlog: record [0-9]+: .*goes backwards \\(([0-9.]+) after ([0-9.]+)\\)")))
      << r.err;
  std::smatch m;
  ASSERT_TRUE(
      std::regex_search(r.err, m, std::regex("goes backwards \\(([0-9.]+) after ([0-9.]+)\\)")));
  EXPECT_NE(m[1].str(), m[2].str());
}

// freeinit-eval-rawlog's command line follows every app's rule.
TEST(CommandLines, EvalRawlogHelpVersionAndBadFlags) {
  const fs::path d = freshDir("eval_cli");
  {
    Process p({FREEINIT_EVAL_RAWLOG_APP, "--help", "--csv", (d / "x.csv").string()}, d, "help");
    EXPECT_EQ(exitCode(p.wait()), 0);
    EXPECT_CONTAINS(p.out(), "Usage: freeinit-eval-rawlog");
  }
  {
    Process p({FREEINIT_EVAL_RAWLOG_APP, kIni}, d, "none");
    EXPECT_EQ(exitCode(p.wait()), 2);
    EXPECT_EQ(lineCount(p.err()), 1u) << p.err();
  }
  {
    Process p({FREEINIT_EVAL_RAWLOG_APP, kIni, kSample, "--fail-velocity", "-1"}, d, "bad");
    EXPECT_EQ(exitCode(p.wait()), 2);
    EXPECT_CONTAINS(p.err(), "freeinit-eval-rawlog: error: --fail-velocity: ");
  }
  EXPECT_EQ(listing(d), (std::set<std::string>{"help.out", "help.err", "none.out", "none.err",
                                               "bad.out", "bad.err"}));
}

}  // namespace
