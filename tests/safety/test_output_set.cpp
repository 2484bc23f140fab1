// The output set (output_set.h): a run's outputs appear whole or not at all, replace the earlier
// run's as a whole and only as a whole (a failed run leaves them as they were), never touch what
// is not ours, never delete a recording, and two sets on one folder exclude each other.
#include <freeinit/app_support/app_config.h>
#include <freeinit/app_support/output_set.h>
#include <freeinit/app_support/result_files.h>
#include <freeinit/app_support/stop_signal.h>
#include <freeinit/io/config_section.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace {

namespace fs = std::filesystem;
using freeinit::app_support::folderSetOptions;
using freeinit::app_support::OutputBusy;
using freeinit::app_support::OutputError;
using freeinit::app_support::OutputSet;
using freeinit::app_support::OutputSetOptions;

fs::path freshDir(const std::string& name) {
  const fs::path d = fs::current_path() / "output_set" / name;
  fs::remove_all(d);
  fs::create_directories(d.parent_path());
  return d;
}

void put(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

std::string get(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

/// Every entry of `dir` (recursively), relative to it.
std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    out.insert(fs::relative(e.path(), dir).string());
  return out;
}

/// An earlier run's outputs (a single start and a start folder of --every) and a file of the
/// user's.
void earlierRun(const fs::path& d) {
  put(d / "initial_state.ini", "earlier\n");
  put(d / "errors_wrt_gt.ini", "earlier\n");
  put(d / "velocity.png", "earlier\n");
  put(d / "start_0001.000" / "initial_state.ini", "earlier\n");
  put(d / "notes.txt", "mine\n");
}

void writeText(OutputSet& set, const std::string& name, const std::string& text) {
  set.write(name, [&](const std::string& p) { put(p, text); });
}

TEST(OutputSet, ReplacesTheEarlierSetAsAWholeAndKeepsWhatIsNotOurs) {
  const fs::path d = freshDir("replace");
  earlierRun(d);
  std::ostringstream log;
  {
    OutputSet set(d.string(), "", folderSetOptions(), log);
    writeText(set, "initial_state.ini", "new\n");
    writeText(set, "static_map.ply", "new\n");
    // Nothing is visible before the install: the earlier set is still whole.
    EXPECT_EQ(get(d / "initial_state.ini"), "earlier\n");
    EXPECT_FALSE(fs::exists(d / "static_map.ply"));
    set.commit();
  }
  EXPECT_EQ(listing(d),
            (std::set<std::string>{"initial_state.ini", "static_map.ply", "notes.txt"}));
  EXPECT_EQ(get(d / "initial_state.ini"), "new\n");
}

TEST(OutputSet, AFailedRunLeavesTheEarlierSetAsItWasAndNoTemporaryFile) {
  const fs::path d = freshDir("abandon");
  earlierRun(d);
  const auto earlier = listing(d);
  std::ostringstream log;
  {
    OutputSet set(d.string(), "", folderSetOptions(), log);
    writeText(set, "initial_state.ini", "new\n");
    set.write("static_map.ply", [](const std::string& p) { put(p + ".tmp", "half"); });
    EXPECT_EQ(set.leftBehind(), "nothing of this run is left in " + d.string() +
                                    ", the earlier outputs there are as they were");
    // destroyed without commit(): a failure on the way
  }
  EXPECT_EQ(listing(d), earlier);
  EXPECT_EQ(get(d / "initial_state.ini"), "earlier\n");
}

TEST(OutputSet, AFailedRunInANewFolderLeavesNoFolder) {
  const fs::path d = freshDir("new_folder") / "a" / "b";
  std::ostringstream log;
  { OutputSet set(d.string(), "", folderSetOptions(), log); }
  EXPECT_FALSE(fs::exists(d.parent_path().parent_path()));
}

TEST(OutputSet, TwoSetsOnOneFolderExcludeEachOther) {
  const fs::path d = freshDir("lock");
  std::ostringstream log;
  {
    OutputSet first(d.string(), "", folderSetOptions(), log);
    try {
      OutputSet second(d.string(), "", folderSetOptions(), log);
      FAIL() << "the second set was not refused";
    } catch (const OutputBusy& e) {
      const std::string m = e.what();
      EXPECT_EQ(m.rfind(d.string() + ": in use by another run (pid " + std::to_string(getpid()), 0),
                0u)
          << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    }
    writeText(first, "initial_state.ini", "first\n");
    first.commit();
  }
  // The lock went with the first set: no file of ours but the outputs remains.
  EXPECT_EQ(listing(d), (std::set<std::string>{"initial_state.ini"}));
  OutputSet again(d.string(), "", folderSetOptions(), log);
  again.commit();
}

TEST(OutputSet, SetsOfFilesNamedAfterDifferentOutputsAreIndependent) {
  const fs::path d = freshDir("stems");
  put(d / "a.rawlog", "earlier a\n");
  put(d / "a.truth.csv", "earlier a\n");
  put(d / "b.rawlog", "b\n");
  put(d / "b.truth.csv", "b\n");
  OutputSetOptions options;
  options.owned = {"a.rawlog", "a.truth.csv", "a.scenario.ini"};
  std::ostringstream log;
  OutputSet a(d.string(), "a", options, log);
  OutputSetOptions b_options;
  b_options.owned = {"b.rawlog"};
  OutputSet b(d.string(), "b", b_options, log);  // another name: not busy
  writeText(a, "a.rawlog", "new a\n");
  a.commit();
  b.abandon();
  EXPECT_EQ(listing(d), (std::set<std::string>{"a.rawlog", "b.rawlog", "b.truth.csv"}));
  EXPECT_EQ(get(d / "a.rawlog"), "new a\n");
}

OutputSetOptions liveOptions() {
  OutputSetOptions o = folderSetOptions();
  o.recording = "live.rawlog";
  o.recording_companion = "stream_stats.ini";
  return o;
}

TEST(OutputSet, AnEarlierRecordingIsRenamedNeverDeleted) {
  const fs::path d = freshDir("recording");
  put(d / "live.rawlog", "earlier recording\n");
  put(d / "stream_stats.ini", "earlier stats\n");
  put(d / "initial_state.ini", "earlier\n");
  std::ostringstream log;
  OutputSet set(d.string(), "", liveOptions(), log);
  const std::string kept = set.keptRecordingName("live.rawlog");
  ASSERT_EQ(kept.rfind("live.", 0), 0u);
  writeText(set, "live.rawlog", "new recording\n");
  writeText(set, "stream_stats.ini", "new stats\n");
  set.commit();
  const std::string stem = kept.substr(0, kept.size() - std::string(".rawlog").size());
  EXPECT_EQ(listing(d), (std::set<std::string>{"live.rawlog", "stream_stats.ini", kept,
                                               stem + ".stream_stats.ini"}));
  EXPECT_EQ(get(d / kept), "earlier recording\n");
  EXPECT_EQ(get(d / (stem + ".stream_stats.ini")), "earlier stats\n");
  EXPECT_EQ(get(d / "live.rawlog"), "new recording\n");
}

// A live run that fails before its state is installed: the earlier set stays whole (its
// recording under its name), this run's recording and statistics are kept beside it.
TEST(OutputSet, ALiveRunThatFailsBeforeItsInstallKeepsItsRecordingBesideTheEarlierSet) {
  const fs::path d = freshDir("recording_abandon");
  put(d / "live.rawlog", "earlier recording\n");
  put(d / "stream_stats.ini", "earlier stats\n");
  put(d / "initial_state.ini", "earlier\n");
  std::ostringstream log;
  std::string left;
  {
    OutputSet set(d.string(), "", liveOptions(), log);
    writeText(set, "live.rawlog", "this run's recording\n");
    writeText(set, "stream_stats.ini", "this run's stats\n");
    writeText(set, "static_map.ply", "not whole\n");
    left = set.leftBehind();
  }
  const auto files = listing(d);
  ASSERT_EQ(files.size(), 5u);
  std::string kept;
  for (const auto& f : files)
    if (f != "live.rawlog" && f.size() > 7 && f.compare(f.size() - 7, 7, ".rawlog") == 0) kept = f;
  ASSERT_EQ(kept.rfind("live.", 0), 0u) << kept;
  const std::string stem = kept.substr(0, kept.size() - 7);
  EXPECT_EQ(files, (std::set<std::string>{"live.rawlog", "stream_stats.ini", "initial_state.ini",
                                          kept, stem + ".stream_stats.ini"}));
  EXPECT_EQ(get(d / "live.rawlog"), "earlier recording\n");
  EXPECT_EQ(get(d / "stream_stats.ini"), "earlier stats\n");
  EXPECT_EQ(get(d / "initial_state.ini"), "earlier\n");
  EXPECT_EQ(get(d / kept), "this run's recording\n");
  EXPECT_EQ(get(d / (stem + ".stream_stats.ini")), "this run's stats\n");
  EXPECT_EQ(left, "this run's recording is kept as " + (d / kept).string() +
                      " with its statistics " + stem + ".stream_stats.ini" +
                      ", the earlier outputs there are as they were");
}

// A live run that fails after its state was installed (a full disk at the map): the folder holds
// this run's state with its recording and statistics, nothing of the earlier run but its
// recording, renamed.
TEST(OutputSet, ALiveRunThatFailsAfterItsStateKeepsTheStateWithItsRecording) {
  const fs::path d = freshDir("recording_after_state");
  put(d / "live.rawlog", "earlier recording\n");
  put(d / "initial_state.ini", "earlier\n");
  put(d / "static_map.ply", "earlier\n");
  std::ostringstream log;
  std::string kept, left;
  {
    OutputSet set(d.string(), "", liveOptions(), log);
    kept = set.keptRecordingName("live.rawlog");
    writeText(set, "initial_state.ini", "new\n");
    set.install({"initial_state.ini"});
    writeText(set, "live.rawlog", "this run's recording\n");
    writeText(set, "stream_stats.ini", "this run's stats\n");
    left = set.leftBehind();
  }
  EXPECT_EQ(listing(d),
            (std::set<std::string>{kept, "initial_state.ini", "live.rawlog", "stream_stats.ini"}));
  EXPECT_EQ(get(d / "initial_state.ini"), "new\n");
  EXPECT_EQ(get(d / "live.rawlog"), "this run's recording\n");
  EXPECT_EQ(get(d / kept), "earlier recording\n");
  EXPECT_EQ(left, "this run's initial_state.ini, live.rawlog and stream_stats.ini are in " +
                      d.string() + ", its other outputs are not");
}

// Statistics whose recording is not there (a recording under another name) are kept too.
TEST(OutputSet, StatisticsWithoutTheirRecordingAreKept) {
  const fs::path d = freshDir("stats_alone");
  put(d / "stream_stats.ini", "earlier stats\n");
  put(d / "initial_state.ini", "earlier\n");
  std::ostringstream log;
  {
    OutputSet set(d.string(), "", folderSetOptions(), log);
    writeText(set, "initial_state.ini", "new\n");
    set.commit();
  }
  const auto files = listing(d);
  ASSERT_EQ(files.size(), 2u);
  const std::string kept = *files.rbegin();
  EXPECT_EQ(kept.rfind("stream_stats.", 0), 0u) << kept;
  EXPECT_EQ(get(d / kept), "earlier stats\n");
}

// Room for ending a run on a full disk: held in the staging folder, never installed, never left.
TEST(OutputSet, TheReserveIsHeldWhileTheRunWorksAndLeavesWithIt) {
  const fs::path d = freshDir("reserve");
  OutputSetOptions options = liveOptions();
  options.reserve_bytes = 64 * 1024;
  std::ostringstream log;
  OutputSet set(d.string(), "", options, log);
  const fs::path reserve = d / ".freeinit.staging" / ".reserve";
  ASSERT_TRUE(fs::exists(reserve));
  EXPECT_EQ(fs::file_size(reserve), 64u * 1024u);
  set.releaseReserve();
  EXPECT_FALSE(fs::exists(reserve));
  set.holdReserve();
  EXPECT_TRUE(fs::exists(reserve));
  writeText(set, "initial_state.ini", "new\n");
  set.commit();
  EXPECT_EQ(listing(d), (std::set<std::string>{"initial_state.ini"}));
}

TEST(OutputSet, TheStateCanBeInstalledBeforeTheRestNeverBesideAnEarlierRunsOutputs) {
  const fs::path d = freshDir("parts");
  earlierRun(d);
  std::ostringstream log;
  OutputSet set(d.string(), "", folderSetOptions(), log);
  writeText(set, "initial_state.ini", "new\n");
  set.install({"initial_state.ini"});
  EXPECT_EQ(listing(d), (std::set<std::string>{".freeinit.lock", ".freeinit.staging",
                                               "initial_state.ini", "notes.txt"}));
  writeText(set, "static_map.ply", "new\n");
  set.commit();
  EXPECT_EQ(listing(d),
            (std::set<std::string>{"initial_state.ini", "static_map.ply", "notes.txt"}));
}

TEST(OutputSet, AnInstallCutByAPowerLossIsFinishedByTheNextRun) {
  // What a run leaves when the machine stops in the middle of installing: the journal, one
  // entry already renamed into place, one still staged, an earlier file not yet removed.
  const fs::path d = freshDir("journal");
  const fs::path staging = d / ".freeinit.staging";
  put(d / "errors_wrt_gt.ini", "earlier\n");
  put(d / "static_map.ply", "installed\n");
  put(staging / "initial_state.ini", "staged\n");
  put(staging / ".install",
      "remove\terrors_wrt_gt.ini\terrors_wrt_gt.ini\ninstall\tstatic_map.ply\tstatic_map.ply\n"
      "install\tinitial_state.ini\tinitial_state.ini\n");
  std::ostringstream log;
  OutputSet set(d.string(), "", folderSetOptions(), log);
  EXPECT_NE(
      log.str().find("Finished installing the outputs of an interrupted run in " + d.string()),
      std::string::npos)
      << log.str();
  EXPECT_EQ(get(d / "initial_state.ini"), "staged\n");
  EXPECT_EQ(get(d / "static_map.ply"), "installed\n");
  EXPECT_FALSE(fs::exists(d / "errors_wrt_gt.ini"));
  set.abandon();  // what the interrupted run installed is its set now: it stays
  EXPECT_EQ(listing(d), (std::set<std::string>{"initial_state.ini", "static_map.ply"}));
}

TEST(OutputSet, TheStagingOfARunThatDiedGoesButItsRecordingIsKept) {
  const fs::path d = freshDir("dead_run");
  put(d / ".freeinit.staging" / "live.rawlog.tmp", "cut recording");
  put(d / ".freeinit.staging" / "initial_state.ini", "dead run\n");
  std::ostringstream log;
  OutputSet set(d.string(), "", liveOptions(), log);
  set.commit();
  const auto files = listing(d);
  ASSERT_EQ(files.size(), 1u);
  const std::string kept = *files.begin();
  EXPECT_EQ(kept.rfind("live.", 0), 0u);
  EXPECT_EQ(get(d / kept), "cut recording");
  EXPECT_NE(log.str().find("Kept the recording of an interrupted run as " + (d / kept).string()),
            std::string::npos)
      << log.str();
  EXPECT_NE(log.str().find("--salvage"), std::string::npos);
}

TEST(OutputSet, AWriteErrorNamesTheFinalFile) {
  const fs::path d = freshDir("error");
  std::ostringstream log;
  OutputSet set(d.string(), "", folderSetOptions(), log);
  try {
    set.write("static_map.ply",
              [](const std::string& p) { throw std::runtime_error(p + ": cannot write: boom"); });
    FAIL();
  } catch (const OutputError& e) {
    EXPECT_EQ(std::string(e.what()), (d / "static_map.ply").string() + ": cannot write: boom");
  }
}

TEST(OutputSet, AStopRequestStopsTheNextWrite) {
  const fs::path d = freshDir("stop");
  std::ostringstream log;
  OutputSet set(d.string(), "", folderSetOptions(), log);
  freeinit::app_support::requestStop(SIGTERM);
  EXPECT_THROW(writeText(set, "initial_state.ini", "x"), freeinit::app_support::Interrupted);
  freeinit::app_support::clearStopRequest();
}

TEST(OutputSet, RefusesAFileAsTheFolder) {
  const fs::path d = freshDir("file");
  put(d, "a file\n");
  std::ostringstream log;
  try {
    OutputSet set(d.string(), "", folderSetOptions(), log);
    FAIL();
  } catch (const OutputError& e) {
    EXPECT_EQ(std::string(e.what()), d.string() + ": not a folder (the outputs need one)");
  }
}

// The result files' table (result_files.h) is the one list: each file is ours in an output folder
// (replaced with the set, never left behind) and enabled by an [output] flag the INI declares.
TEST(ResultFiles, EveryFileIsOwnedByAFolderSetAndHasADeclaredFlag) {
  using namespace freeinit::app_support;
  const std::vector<std::string> owned = folderOutputNames();
  std::set<std::string> flags;
  for (const auto& k : outputSection().keys())
    if (k.unit == "bool") flags.insert(k.name);
  std::set<std::string> keys;
  for (const ResultFile& f : resultFiles()) {
    EXPECT_NE(std::find(owned.begin(), owned.end(), f.name), owned.end()) << f.name;
    keys.insert(f.key);
  }
  EXPECT_EQ(keys, flags);
  EXPECT_EQ(resultFileNames().size(), resultFiles().size());
}

TEST(ResultFiles, WritesWhatOutputEnablesAndWhatHasContent) {
  using namespace freeinit::app_support;
  freeinit::InitResult r;  // no map and no velocities: no snapshot has anything to draw
  r.trajectory.resize(2);
  OutputParams output;  // snapshots enabled, as by default
  output.simplemap = false;
  output.velocities = false;
  const fs::path d = freshDir("result_files");
  std::ostringstream log;
  {
    OutputSet set(d.string(), "", folderSetOptions(), log);
    writeResultFiles(set, "start_0001.000/", output, r, {});
    set.commit();
  }
  EXPECT_EQ(listing(d), (std::set<std::string>{"start_0001.000", "start_0001.000/static_map.ply",
                                               "start_0001.000/trajectory_tum.txt"}));
}

}  // namespace
