// A user's data and earlier results are safe, second pass: what lies beside a recording, a gzip
// stream whose checksum fails, and the bounds of what a flag may ask for. Each case runs the app
// as a process and asserts the exit status, the message and what is left on disk.
#include <zlib.h>

#include <filesystem>
#include <fstream>
#include <string>

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

/// A complete run of freeinit on the sample, as a user starts it (made once for the tests
/// that need one): its output folder, and what it printed in "run.out" beside it.
const fs::path& sampleRun() {
  static const fs::path out = [] {
    const fs::path d = freshDir("sample_run");
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

}  // namespace
