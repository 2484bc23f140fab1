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

}  // namespace
