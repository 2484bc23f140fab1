// A user's data and earlier results are safe, second pass: what lies beside a recording, a gzip
// stream whose checksum fails, the bounds of what a flag may ask for, live recordings on a full
// disk and earlier results that only a complete new set replaces. Each case runs the app as a
// process and asserts the exit status, the message and what is left on disk.
#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <zlib.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <string>
#include <vector>

#include "app_process.h"

namespace {

using namespace app_test;
namespace fs = std::filesystem;

const std::string kSrc = FREEINIT_SOURCE_DIR;
const std::string kIni = kSrc + "/ini/freeinit.ini";
const std::string kSample = kSrc + "/rawlogs/dyna_01.rawlog";

// A FIFO where the seek index goes (`--start` reads an index first): the run neither blocks nor
// touches it.
TEST(SeekIndex, AFifoBesideTheRecordingIsNeitherReadNorReplaced) {
  const fs::path d = freshDir("index_fifo");
  const fs::path rawlog = d / "x.rawlog";
  fs::copy_file(kSample, rawlog);
  const fs::path fifo = d / "x.rawlog.freeinit.idx";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  Process p(
      {FREEINIT_APP, kIni, rawlog.string(), "--start", "0.3", "-q", "--out", (d / "out").string()},
      d, "run");
  EXPECT_EQ(exitCode(p.wait(60)), 0) << p.err();
  EXPECT_TRUE(fs::is_fifo(fifo));
  EXPECT_TRUE(fs::exists(d / "out" / "initial_state.ini"));
}

// A user thinking in ms (`-d 500`): freeinit-sim says how much it will write before it starts,
// and refuses what does not fit on the disk, naming the flags, before simulating anything.
TEST(Simulator, ARecordingTooLargeForTheDiskIsRefusedBeforeAnyWork) {
  const fs::path d = freshDir("sim_too_large");
  const fs::path mnt = d / "mnt";
  const std::string script = std::string(FREEINIT_SIM_APP) + " -p dyna_01 -d 500 -n 60000 -o " +
                             mnt.string() + "/x.rawlog > " + (d / "sim.out").string() + " 2> " +
                             (d / "sim.err").string() + "; echo $? > " + (d / "sim.rc").string() +
                             "; ls -A " + mnt.string() + " > " + (d / "sim.left").string();
  if (!withSmallDisk(mnt, "2m", script, d / "unshare.log"))
    GTEST_SKIP() << "cannot mount a tmpfs here (not root?)";
  EXPECT_EQ(readText(d / "sim.rc"), "1\n") << readText(d / "unshare.log");
  const std::string err = readText(d / "sim.err");
  EXPECT_EQ(lineCount(err), 1u) << err;
  EXPECT_CONTAINS(err,
                  "freeinit-sim: error: -d 500 -n 60000: 5000 point clouds of 60000 points, "
                  "about 7.5 GB of rawlog, more than the ");
  EXPECT_CONTAINS(err, "(-d is in seconds)");
  EXPECT_EQ(readText(d / "sim.out"), "");
  EXPECT_EQ(readText(d / "sim.left"), "");
}

/// A complete run of freeinit on the sample, as a user starts it (made once per test process
/// for the tests that need one; a folder per process, since ctest runs tests side by side): its
/// output folder, and what it printed in "run.out" beside it.
const fs::path& sampleRun() {
  static const fs::path out = [] {
    const fs::path d = freshDir("sample_run_" + std::to_string(getpid()));
    Process p({FREEINIT_APP, kIni, kSample, "--out", (d / "out").string()}, d, "run");
    EXPECT_EQ(exitCode(p.wait()), 0) << p.err();
    return d / "out";
  }();
  return out;
}

/// The sample's records (its decompressed stream).
std::string decompressed(const std::string& path) {
  gzFile f = gzopen(path.c_str(), "rb");
  std::string out;
  if (f == nullptr) return out;
  char buf[1 << 16];
  for (int n; (n = gzread(f, buf, sizeof buf)) > 0;) out.append(buf, static_cast<std::size_t>(n));
  gzclose(f);
  return out;
}

/// `data` as gzip of stored blocks: a byte flipped in the file then changes that byte of the
/// data only, and the stream decodes to its end, where its CRC-32 fails.
void writeStoredGzip(const std::string& path, const std::string& data) {
  gzFile f = gzopen(path.c_str(), "wb0");
  ASSERT_NE(f, nullptr);
  ASSERT_EQ(gzwrite(f, data.data(), static_cast<unsigned>(data.size())),
            static_cast<int>(data.size()));
  ASSERT_EQ(gzclose(f), Z_OK);
}

// A byte flipped inside the gzip data: the default run reads the window and checks its records
// (not the stream's CRC-32, which is at its end: README, "What a run verifies"); --check-all
// reads to the end, where the CRC fails: the whole stream is suspect, so the run fails saying
// so, without naming a record as the damaged one, and writes nothing.
TEST(Integrity, AFailedGzipChecksumFailsACheckAllRunSayingTheWholeStreamIsSuspect) {
  const fs::path d = freshDir("gzip_crc");
  const std::string good = (d / "good.rawlog").string(), bad = (d / "bad.rawlog").string();
  writeStoredGzip(good, decompressed(kSample));
  // In the file, after the checksum was computed: a byte of a point's coordinate in the first
  // point cloud (record 1), a value, not structure.
  std::string file = readText(good);
  const std::size_t at = file.find("CPointsMapDoppler") + 400;
  ASSERT_LT(at, file.size());
  file[at] = static_cast<char>(file[at] ^ 0x10);
  std::ofstream(bad, std::ios::binary)
      .write(file.data(), static_cast<std::streamsize>(file.size()));

  Process ok({FREEINIT_APP, kIni, good, "--check-all", "-q", "--out", (d / "good").string()}, d,
             "good");
  EXPECT_EQ(exitCode(ok.wait()), 0) << ok.err();

  Process checked({FREEINIT_APP, kIni, bad, "--check-all", "-q", "--out", (d / "bad").string()}, d,
                  "bad");
  EXPECT_EQ(exitCode(checked.wait()), 1);
  const std::string err = checked.err();
  EXPECT_EQ(lineCount(err), 1u) << err;
  EXPECT_CONTAINS(err, "freeinit: error: " + bad + ": the gzip stream's CRC-32 does not match");
  EXPECT_CONTAINS(err, "every record read from it is suspect");
  EXPECT_EQ(err.find("record 3"), std::string::npos) << err;  // no record blamed
  EXPECT_FALSE(fs::exists(d / "bad"));
}

// Every error once, on the error stream: a window the checks refuse (an IMU slower than
// [input] min_imu_rate) gives one line there and none on the output.
TEST(Messages, AnErrorIsPrintedOnceOnTheErrorStream) {
  const fs::path d = freshDir("error_once");
  const fs::path ini = d / "slow_imu.ini";
  std::ofstream(ini) << "[input]\nmin_imu_rate = 1000\n";
  Process p({FREEINIT_APP, ini.string(), kSample, "-q", "--out", (d / "out").string()}, d, "run");
  EXPECT_EQ(exitCode(p.wait()), 1);
  const std::string err = p.err();
  EXPECT_EQ(lineCount(err), 1u) << err;
  EXPECT_CONTAINS(err, "freeinit: error: " + kSample + ": record ");
  EXPECT_CONTAINS(err, "[input] min_imu_rate");
  EXPECT_EQ(p.out().find("rror"), std::string::npos) << p.out();
}

// The state comes right after the reading: the effective configuration (~100 lines) is
// written to effective_config.ini, and listed on the output only with --print-config.
TEST(Messages, TheStateComesFirstAndTheConfigurationOnlyOnRequest) {
  const fs::path& run = sampleRun();
  const std::string out = readText(run.parent_path() / "run.out");
  EXPECT_EQ(out.find("Effective configuration"), std::string::npos) << out;
  EXPECT_LT(lineCount(out), 30u) << out;
  EXPECT_CONTAINS(out, "Initialization: ok");
  EXPECT_CONTAINS(readText(run / "effective_config.ini"), "max_point_rate");

  const fs::path d = freshDir("config_on_request");
  Process listed(
      {FREEINIT_APP, kIni, kSample, "-q", "--print-config", "--out", (d / "listed").string()}, d,
      "listed");
  ASSERT_EQ(exitCode(listed.wait()), 0) << listed.err();
  EXPECT_CONTAINS(listed.out(), "Effective configuration (" + kIni + "):");
  EXPECT_CONTAINS(listed.out(), "max_point_rate");
}

// An output of an earlier run where the recording or the configuration goes: one line naming
// the file, what it is and what to give instead; nothing is run (exit 2, a bad command line).
TEST(Messages, AnOutputGivenAsInputIsRecognisedAsOurs) {
  const fs::path& run = sampleRun();
  const fs::path d = freshDir("outputs_as_input");
  const std::vector<std::pair<std::string, std::string>> outputs = {
      {"static_map.simplemap", "is an MRPT simple map (a run's static map"},
      {"static_map.ply", "is a PLY point cloud (a run's static map"},
      {"static_map.png", "is a PNG image (a run's snapshot"},
      {"velocity.png", "is a PNG image (a run's snapshot"},
      {"initial_state.ini", "is the initial state a run wrote (initial_state.ini)"},
      {"errors_wrt_gt.ini",
       "is the report of errors against ground truth a run wrote (errors_wrt_gt.ini)"},
      {"velocimeter.csv", "is the velocity table a run wrote (velocimeter.csv)"},
      {"trajectory_tum.txt", "is the trajectory a run wrote (trajectory_tum.txt)"}};
  bool with_ini = false;  // alone and after a configuration, in turn
  for (const auto& [name, what] : outputs) {
    // The messages of every kind are in FreeInitAppParams.OutputsOfARunAreNamed (in-process);
    // here one of each file type as a user gives it.
    if (name == "velocity.png" || name == "errors_wrt_gt.ini" || name == "trajectory_tum.txt")
      continue;
    const std::string file = (run / name).string();
    with_ini = !with_ini;
    {
      std::vector<std::string> argv = {FREEINIT_APP};
      if (with_ini) argv.push_back(kIni);
      argv.insert(argv.end(), {file, "-q", "--out", (d / "out").string()});
      Process p(argv, d, "run");
      EXPECT_EQ(exitCode(p.wait()), 2) << name;
      const std::string err = p.err();
      EXPECT_EQ(lineCount(err), 1u) << err;
      EXPECT_CONTAINS(err, "freeinit: error: <input.rawlog> '" + file + "' " + what);
      EXPECT_CONTAINS(err, "not a recording: give the recording the run read (an MRPT .rawlog");
      EXPECT_FALSE(fs::exists(d / "out")) << name;
    }
  }
  // A result where the configuration goes.
  const std::string state = (run / "initial_state.ini").string();
  Process p({FREEINIT_APP, state, kSample, "-q", "--out", (d / "out").string()}, d, "config");
  EXPECT_EQ(exitCode(p.wait()), 2);
  EXPECT_EQ(lineCount(p.err()), 1u) << p.err();
  EXPECT_CONTAINS(p.err(), "<config.ini> '" + state +
                               "' is the initial state a run wrote (initial_state.ini), not a "
                               "configuration: give an INI configuration such as "
                               "ini/freeinit.ini");
}

// --every 0 and starts so close that their windows pile up are refused naming the flag, before
// any work (the earlier bad_alloc at --every 1e-5); nothing is left behind.
TEST(Bounds, EveryIsRefusedWhenItWouldKeepTooManyWindowsOpen) {
  const fs::path d = freshDir("every_bounds");
  Process zero({FREEINIT_APP, kIni, kSample, "--every", "0", "--out", (d / "out").string()}, d,
               "zero");
  EXPECT_EQ(exitCode(zero.wait()), 2);
  EXPECT_EQ(zero.err(),
            "freeinit: error: --every: 0 is out of range: accepted > 0; see 'freeinit --help'\n");

  Process tiny({FREEINIT_APP, kIni, kSample, "--every", "1e-5", "--out", (d / "out").string()}, d,
               "tiny");
  EXPECT_EQ(exitCode(tiny.wait(30)), 1);
  EXPECT_EQ(lineCount(tiny.err()), 1u) << tiny.err();
  EXPECT_CONTAINS(tiny.err(),
                  "freeinit: error: --every 1e-05: starts 1e-05 s apart keep about 50000 "
                  "initializations open at once (each holds its 0.5 s window, [window] "
                  "duration); at most 32: give --every 0.015625 or more");
  EXPECT_FALSE(fs::exists(d / "out"));
}

// Starts less than a millisecond apart get folders of their own (named with the decimals they
// need), never one another's.
TEST(Bounds, StartsCloserThanAMillisecondGetFoldersOfTheirOwn) {
  const fs::path d = freshDir("close_starts");
  std::ofstream(d / "starts.txt") << "0.1\n0.1001\n0.1002\n";
  Process p({FREEINIT_APP, kIni, kSample, "-q", "--starts", (d / "starts.txt").string(), "--out",
             (d / "out").string()},
            d, "run");
  EXPECT_EQ(exitCode(p.wait()), 0) << p.err();
  for (const char* name : {"start_0000.1000", "start_0000.1001", "start_0000.1002"})
    EXPECT_TRUE(fs::exists(d / "out" / name / "initial_state.ini")) << name << "\n" << p.out();
  EXPECT_EQ(readText(d / "out" / "starts.csv").find("start_0000.100,"), std::string::npos);
}

// A run at many starts killed (SIGKILL: no handler runs) leaves its staging folder and lock,
// both hidden, and nothing beside them that passes for a result; the next run on the folder
// discards them and leaves its own complete set only.
TEST(Bounds, AKilledRunAtManyStartsLeavesNothingThatPassesForAResult) {
  const fs::path d = freshDir("every_killed");
  const fs::path out = d / "out";
  bool killed = false;
  for (int attempt = 0; attempt < 5 && !killed; ++attempt) {
    Process p({FREEINIT_APP, kIni, kSample, "-q", "--every", "0.1", "--out", out.string()}, d,
              "killed");
    // Killed once a start's outputs are staged.
    waitUntil(
        [&] { return !p.running() || fs::exists(out / ".freeinit.staging" / "start_0000.000"); });
    p.signal(SIGKILL);
    killed = killedBy(p.wait(), SIGKILL);
  }
  ASSERT_TRUE(killed) << "the run always ended before it could be killed";
  for (const auto& e : fs::directory_iterator(out))
    EXPECT_EQ(e.path().filename().string().front(), '.') << e.path();  // hidden only

  Process next({FREEINIT_APP, kIni, kSample, "-q", "--start", "0.2", "--out", out.string()}, d,
               "next");
  ASSERT_EQ(exitCode(next.wait()), 0) << next.err();
  EXPECT_FALSE(fs::exists(out / ".freeinit.staging"));
  EXPECT_FALSE(fs::exists(out / ".freeinit.lock"));
  EXPECT_FALSE(fs::exists(out / "start_0000.000"));
  EXPECT_TRUE(fs::exists(out / "initial_state.ini"));
}

// --- live recordings on a full disk; earlier results replaced only by a complete new set ---

/// Every file under `dir` with its content.
std::map<std::string, std::string> contents(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) out[fs::relative(e.path(), dir).string()] = readText(e.path());
  return out;
}

std::size_t wholeRecords(const fs::path& rawlog) {
  return freeinit::mrpt_plugins::readRawlog(rawlog.string()).size();
}

/// The names in `dir` matching `pattern`.
std::vector<std::string> matching(const fs::path& dir, const std::string& pattern) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string n = e.path().filename().string();
    if (std::regex_match(n, std::regex(pattern))) out.push_back(n);
  }
  std::sort(out.begin(), out.end());
  return out;
}

const char* const kKeptRecording = "live\\.[0-9]{8}-[0-9]{6}(-[0-9]+)?\\.rawlog";

/// A finished freeinit-online run into `out`: the sample streamed, the whole set written.
void finishedLiveRun(const fs::path& out, const fs::path& d) {
  Process online({FREEINIT_ONLINE_APP, kIni, "-o", out.string(), "-p", "0", "-i", "5"}, d,
                 "finished");
  const int port = listeningPort(online);
  ASSERT_GT(port, 0) << online.err();
  Process stream({FREEINIT_STREAM_APP, "-i", kSample, "-p", std::to_string(port)}, d,
                 "finished_stream");
  ASSERT_EQ(exitCode(online.wait()), 0) << online.err();
  stream.wait();
  for (const char* f : {"initial_state.ini", "effective_config.ini", "static_map.ply",
                        "static_map.simplemap", "static_map.png", "velocity.png",
                        "trajectory_tum.txt", "velocimeter.csv", "live.rawlog", "stream_stats.ini"})
    ASSERT_TRUE(fs::exists(out / f)) << f;
}

/// freeinit-online on a `size` tmpfs (its output folder `<mnt>/out`, prepared by `prepare`),
/// fed by freeinit-stream with `stream_args`; the exit code, output and errors go to d/online.*,
/// and what the run left is copied to d/left (the tmpfs goes with the namespace). False when no
/// tmpfs can be mounted here.
bool liveOnSmallDisk(const fs::path& d, const std::string& size, const std::string& prepare,
                     const std::string& stream_args) {
  const fs::path mnt = d / "mnt";
  const std::string out = (mnt / "out").string(), log = (d / "online.out").string();
  const std::string script =
      "mkdir -p " + out + "; " + prepare + "; " + FREEINIT_ONLINE_APP + " " + kIni + " -o " + out +
      " -p 0 -i 1 > " + log + " 2> " + (d / "online.err").string() +
      " & pid=$!; port=; for i in $(seq 1 3000); do port=$(sed -n "
      "\"s/.*Listening on UDP 127.0.0.1:\\([0-9]*\\).*/\\1/p\" " +
      log + "); [ -n \"$port\" ] && break; kill -0 $pid 2>/dev/null || break; sleep 0.01; done; " +
      FREEINIT_STREAM_APP + " " + stream_args + " -p ${port:-9} > " + (d / "stream.out").string() +
      " 2>&1; wait $pid; echo $? > " + (d / "online.rc").string() + "; cp -a " + out + " " +
      (d / "left").string();
  return withSmallDisk(mnt, size, script, d / "unshare.log");
}

// The disk fills while freeinit-online records, after the window closed: the recording keeps
// every whole record up to there and reads without error, stream_stats.ini says why and when it
// stopped, the state stays with them, and one line says so, naming the file (no MRPT text).
TEST(LiveFullDisk, TheRecordingIsKeptUpToItsLastWholeRecordWithTheStateAndTheStatistics) {
  const fs::path d = freshDir("live_full_disk");
  if (!liveOnSmallDisk(d, "2m", "true", "-P dyna_01 -d 3 -n 8000"))
    GTEST_SKIP() << "cannot mount a tmpfs here (not root?)";
  const std::string out = (d / "mnt" / "out").string();
  EXPECT_EQ(readText(d / "online.rc"), "1\n") << readText(d / "unshare.log");
  const std::string err = readText(d / "online.err");
  EXPECT_EQ(lineCount(err), 1u) << err;
  std::smatch m;
  ASSERT_TRUE(std::regex_match(
      err, m,
      std::regex("freeinit-online: error: " + out +
                 "/live\\.rawlog: the recording stopped after ([0-9]+) whole records \\([0-9.]+ "
                 "s of the stream\\): no space left on the device \\(" +
                 out +
                 " is full\\); this run's effective_config\\.ini, initial_state\\.ini, "
                 "live\\.rawlog and stream_stats\\.ini are in " +
                 out + ", its other outputs are not\n")))
      << err;
  const std::size_t records = std::stoul(m[1]);
  EXPECT_GT(records, 100u);
  const fs::path left = d / "left";
  EXPECT_EQ(listing(left), (std::set<std::string>{"effective_config.ini", "initial_state.ini",
                                                  "live.rawlog", "stream_stats.ini"}));
  EXPECT_EQ(wholeRecords(left / "live.rawlog"), records);
  const std::string stats = readText(left / "stream_stats.ini");
  EXPECT_CONTAINS(stats, "recorded            = " + std::to_string(records) + "\n");
  EXPECT_CONTAINS(stats,
                  "recording_stopped   = no space left on the device (" + out + " is full)\n");
  EXPECT_TRUE(std::regex_search(stats, std::regex("recording_stopped_after_s = [0-9.]+ ")));
  EXPECT_TRUE(std::regex_search(stats, std::regex("recording_last_stamp = 17[0-9]{8}\\.[0-9]+ ")));
  EXPECT_CONTAINS(readText(left / "initial_state.ini"), "status    = ok");
  // What was recorded reproduces the state offline.
  Process offline(
      {FREEINIT_APP, kIni, (left / "live.rawlog").string(), "-q", "--out", (d / "off").string()}, d,
      "offline");
  EXPECT_EQ(exitCode(offline.wait()), 0) << offline.err();
  EXPECT_EQ(readText(d / "off" / "initial_state.ini"), readText(left / "initial_state.ini"));
}

// The disk fills before the window closes: the earlier run's outputs stay as they were, and
// this run's recording (readable) and statistics are kept beside them under a name with their
// time.
TEST(LiveFullDisk, BeforeTheWindowClosesTheEarlierSetStaysAndTheRecordingIsKeptBeside) {
  const fs::path d = freshDir("live_full_disk_early");
  const fs::path earlier = d / "earlier";
  fs::create_directories(earlier);
  for (const char* f : {"initial_state.ini", "static_map.ply", "velocity.png", "live.rawlog",
                        "stream_stats.ini", "trajectory_tum.txt"})
    std::ofstream(earlier / f) << "earlier " << f << "\n";
  if (!liveOnSmallDisk(d, "300k", "cp " + earlier.string() + "/* " + (d / "mnt/out").string(),
                       "-P dyna_01 -d 3 -n 8000"))
    GTEST_SKIP() << "cannot mount a tmpfs here (not root?)";
  const std::string out = (d / "mnt" / "out").string();
  EXPECT_EQ(readText(d / "online.rc"), "1\n") << readText(d / "unshare.log");
  const fs::path left = d / "left";
  const auto kept = matching(left, kKeptRecording);
  ASSERT_EQ(kept.size(), 1u);
  const std::string stem = kept[0].substr(0, kept[0].size() - 7);
  const std::string err = readText(d / "online.err");
  std::smatch m;
  ASSERT_TRUE(std::regex_match(
      err, m,
      std::regex("freeinit-online: error: " + out +
                 "/live\\.rawlog: the recording stopped after ([0-9]+) whole records \\([0-9.]+ "
                 "s of the stream, before the window closed\\): no space left on the device \\(" +
                 out + " is full\\); this run's recording is kept as " + out + "/" + stem +
                 "\\.rawlog with its statistics " + stem +
                 "\\.stream_stats\\.ini, the earlier outputs there are as they were\n")))
      << err;
  auto now = contents(left);
  EXPECT_EQ(wholeRecords(left / kept[0]), std::stoul(m[1]));
  EXPECT_CONTAINS(now[stem + ".stream_stats.ini"], "recording_stopped   = no space left");
  now.erase(kept[0]);
  now.erase(stem + ".stream_stats.ini");
  EXPECT_EQ(now, contents(earlier));
}

// The disk fills at the end, while the map is written: the message says what is there (the
// state, the recording, the statistics), not that nothing is.
TEST(LiveFullDisk, AtTheEndTheMessageSaysWhatIsLeft) {
  const fs::path d = freshDir("live_full_disk_end");
  if (!liveOnSmallDisk(d, "2700k", "true", "-i " + kSample))
    GTEST_SKIP() << "cannot mount a tmpfs here (not root?)";
  const std::string out = (d / "mnt" / "out").string();
  EXPECT_EQ(readText(d / "online.rc"), "1\n") << readText(d / "unshare.log");
  const std::string err = readText(d / "online.err");
  EXPECT_TRUE(std::regex_match(
      err,
      std::regex("freeinit-online: error: " + out +
                 "/static_map\\.[a-z]+: cannot be written: no space left on the device \\(" + out +
                 " is full\\); this run's effective_config\\.ini, "
                 "initial_state\\.ini, live\\.rawlog and stream_stats\\.ini are in " +
                 out + ", its other outputs are not\n")))
      << err;
  const fs::path left = d / "left";
  EXPECT_EQ(listing(left), (std::set<std::string>{"effective_config.ini", "initial_state.ini",
                                                  "live.rawlog", "stream_stats.ini"}));
  EXPECT_GT(wholeRecords(left / "live.rawlog"), 300u);
}

// A run that receives nothing leaves the finished run's outputs as they were, every file.
TEST(EarlierOutputs, ALiveRunThatReceivesNothingLeavesTheFinishedRunAsItWas) {
  const fs::path d = freshDir("earlier_no_data");
  const fs::path out = d / "live";
  finishedLiveRun(out, d);
  const auto before = contents(out);
  Process online({FREEINIT_ONLINE_APP, kIni, "-o", out.string(), "-p", "0", "-w", "1"}, d,
                 "nothing");
  EXPECT_EQ(exitCode(online.wait()), 1);
  EXPECT_EQ(online.err(),
            "freeinit-online: error: live stream: no data received within 1 s; nothing of this "
            "run is left in " +
                out.string() + ", the earlier outputs there are as they were\n");
  EXPECT_EQ(contents(out), before);
  EXPECT_EQ(listing(out).size(), before.size());  // no staging folder, no lock
}

/// Starts freeinit-online on `out` fed by freeinit-stream `stream_args` and SIGKILLs it when
/// `ready` holds (polled), or when it ends.
void killedLiveRun(const fs::path& out, const fs::path& d,
                   const std::vector<std::string>& stream_args,
                   const std::function<bool(Process&)>& ready) {
  Process online({FREEINIT_ONLINE_APP, kIni, "-o", out.string(), "-p", "0", "-i", "30"}, d,
                 "killed");
  const int port = listeningPort(online);
  ASSERT_GT(port, 0);
  std::vector<std::string> args = {FREEINIT_STREAM_APP, "-p", std::to_string(port)};
  args.insert(args.end(), stream_args.begin(), stream_args.end());
  Process stream(args, d, "killed_stream");
  EXPECT_TRUE(waitUntil([&] { return ready(online) || !online.running(); }));
  online.signal(SIGKILL);
  EXPECT_TRUE(killedBy(online.wait(), SIGKILL));
  stream.signal(SIGKILL);
  stream.wait();
}

// A run killed after its state was written (its set replaced the finished one): the next run,
// receiving nothing, keeps that state, and keeps the killed run's recording, saying so.
TEST(EarlierOutputs, AKilledRunsStateIsNotRemovedByTheNextRun) {
  const fs::path d = freshDir("earlier_killed");
  const fs::path out = d / "live";
  finishedLiveRun(out, d);
  killedLiveRun(out, d, {"-P", "dyna_01", "-n", "8000", "-d", "3", "-x", "0.5"},
                [](Process& p) { return p.out().find("State written") != std::string::npos; });
  const std::string state = readText(out / "initial_state.ini");
  EXPECT_CONTAINS(state, "status    = ok");
  EXPECT_EQ(matching(out, kKeptRecording).size(), 1u);  // the finished run's, renamed
  Process next({FREEINIT_ONLINE_APP, kIni, "-o", out.string(), "-p", "0", "-w", "1"}, d, "next");
  EXPECT_EQ(exitCode(next.wait()), 1);
  EXPECT_CONTAINS(next.err(), "nothing of this run is left in " + out.string() +
                                  ", the earlier outputs there are as they were\n");
  EXPECT_EQ(readText(out / "initial_state.ini"), state);
  EXPECT_TRUE(fs::exists(out / "effective_config.ini"));
  std::smatch m;
  const std::string log = next.out();
  ASSERT_TRUE(std::regex_search(
      log, m, std::regex("Kept the recording of an interrupted run as (\\S+\\.rawlog)")))
      << log;
  EXPECT_TRUE(fs::exists(std::string(m[1])));
  EXPECT_EQ(matching(out, kKeptRecording).size(), 2u);
}

// A run killed before its window closed: the finished run's outputs stay whole, with the killed
// run's recording beside them once the next run has moved it out.
TEST(EarlierOutputs, ARunKilledBeforeItsStateLeavesTheFinishedRunWhole) {
  const fs::path d = freshDir("earlier_killed_early");
  const fs::path out = d / "live";
  finishedLiveRun(out, d);
  const auto before = contents(out);
  const fs::path staged = out / ".freeinit.staging" / "live.rawlog.tmp";
  killedLiveRun(out, d, {"-i", kSample, "-x", "0.1"}, [&](Process&) {
    std::error_code ec;
    return fs::file_size(staged, ec) > 100000 && !ec;
  });
  EXPECT_EQ(readText(out / "initial_state.ini"), before.at("initial_state.ini"));
  Process next({FREEINIT_ONLINE_APP, kIni, "-o", out.string(), "-p", "0", "-w", "0.5"}, d, "next");
  EXPECT_EQ(exitCode(next.wait()), 1);
  auto now = contents(out);
  const auto kept = matching(out, kKeptRecording);
  ASSERT_EQ(kept.size(), 1u);
  now.erase(kept[0]);
  EXPECT_EQ(now, before);
}

// freeinit --out on a live run's folder: the earlier recording and its statistics are kept as a
// pair under a name with their time, as freeinit-online keeps them; never left under their
// names beside the new state, never deleted.
TEST(EarlierOutputs, OfflineOnALiveRunsFolderKeepsTheRecordingAndItsStatisticsAsAPair) {
  const fs::path d = freshDir("earlier_offline_on_live");
  const fs::path out = d / "live";
  finishedLiveRun(out, d);
  const std::string recording = readText(out / "live.rawlog");
  const std::string stats = readText(out / "stream_stats.ini");
  Process offline(
      {FREEINIT_APP, kIni, kSrc + "/rawlogs/stat_01.rawlog", "-q", "--out", out.string()}, d,
      "offline");
  EXPECT_EQ(exitCode(offline.wait()), 0) << offline.err();
  EXPECT_FALSE(fs::exists(out / "live.rawlog"));
  EXPECT_FALSE(fs::exists(out / "stream_stats.ini"));
  const auto kept = matching(out, kKeptRecording);
  ASSERT_EQ(kept.size(), 1u);
  const std::string stem = kept[0].substr(0, kept[0].size() - 7);
  EXPECT_EQ(readText(out / kept[0]), recording);
  EXPECT_EQ(readText(out / (stem + ".stream_stats.ini")), stats);
  EXPECT_TRUE(fs::exists(out / "errors_wrt_gt.ini"));  // the new set, whole
}

}  // namespace
