// A user's data and earlier results are safe, second pass: what lies beside a recording, a gzip
// stream whose checksum fails, and the bounds of what a flag may ask for. Each case runs the app
// as a process and asserts the exit status, the message and what is left on disk.
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

}  // namespace
