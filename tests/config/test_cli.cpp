// Every main's command line as a user runs it, each case in an empty folder: --help and
// --version print and exit 0; a bad command line exits 2 with one line naming the flag; a bad
// INI exits 1 with one line naming the file, the line and the key; and in every case the folder
// stays empty (nothing simulated, streamed, recorded or written).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

const std::string kSrc = FREEINIT_SOURCE_DIR;

struct Outcome {
  int code = -1;
  std::string out, err;
  std::vector<std::string> left;  ///< what the run left in its folder
};

std::string readText(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

std::string shellQuote(const std::string& s) {
  std::string q = "'";
  for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Runs `exe args` in <tmp>/<name>/run (created empty); `files` are written to <tmp>/<name>/ first
// (outside the run folder, reachable as ../<file>).
Outcome run(const std::string& name, const std::string& exe, const std::vector<std::string>& args,
            const std::vector<std::pair<std::string, std::string>>& files = {}) {
  const fs::path base = fs::temp_directory_path() / "freeinit_test_cli" / name;
  fs::remove_all(base);
  fs::create_directories(base / "run");
  for (const auto& [f, text] : files) std::ofstream(base / f) << text;
  std::string cmd = "cd " + shellQuote((base / "run").string()) + " && " + shellQuote(exe);
  for (const auto& a : args) cmd += " " + shellQuote(a);
  cmd += " > " + shellQuote((base / "stdout").string()) + " 2> " +
         shellQuote((base / "stderr").string()) + " < /dev/null";
  const int status = std::system(cmd.c_str());
  Outcome r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = readText(base / "stdout");
  r.err = readText(base / "stderr");
  for (const auto& e : fs::directory_iterator(base / "run"))
    r.left.push_back(e.path().filename().string());
  return r;
}

std::size_t lines(const std::string& s) {
  std::size_t n = 0;
  for (const char c : s) n += c == '\n';
  return n;
}

#define EXPECT_CONTAINS(haystack, needle) \
  EXPECT_NE(std::string(haystack).find(needle), std::string::npos) << (haystack)

// --help: usage with the defaults on stdout, exit 0, nothing else done.
void expectHelp(const std::string& name, const std::string& exe,
                const std::vector<std::string>& defaults) {
  SCOPED_TRACE(name);
  const Outcome r = run(name + "_help", exe, {"--help"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_CONTAINS(r.out, "Usage: ");
  for (const auto& d : defaults) EXPECT_CONTAINS(r.out, "(default: " + d + ")");
  EXPECT_TRUE(r.left.empty()) << r.left.front();
  const Outcome v = run(name + "_version", exe, {"--version"});
  EXPECT_EQ(v.code, 0) << v.err;
  EXPECT_CONTAINS(v.out, " 0.1.0\n");
  EXPECT_EQ(lines(v.out), 1u);
  EXPECT_TRUE(v.left.empty());
}

// A bad command line: exit 2, one line on stderr with `message`, nothing done.
void expectUsageError(const std::string& name, const std::string& exe,
                      const std::vector<std::string>& args, const std::string& message) {
  SCOPED_TRACE(name);
  const Outcome r = run(name, exe, args);
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_CONTAINS(r.err, message);
  EXPECT_EQ(r.out, "");
  EXPECT_TRUE(r.left.empty()) << r.left.front();
}

const std::string kRawlog = kSrc + "/rawlogs/stat_01.rawlog";

}  // namespace

TEST(CommandLine, Freeinit) {
  const std::string exe = FREEINIT_APP;
  expectHelp("freeinit", exe,
             {"freeinit_out; without <config.ini> a new folder for each run, "
              "freeinit_out/<input>.<time>"});
  const std::string ini = kSrc + "/ini/freeinit.ini";
  expectUsageError("fi_typo_after", exe, {ini, kRawlog, "--ouput", "out/x"},
                   "freeinit: error: --ouput: unknown option; see 'freeinit --help'");
  expectUsageError("fi_typo_before", exe, {"--ouput", "out/x", ini, kRawlog},
                   "freeinit: error: --ouput: unknown option");
  expectUsageError("fi_nothing", exe, {}, "freeinit: error: missing <input.rawlog>");
  // One argument is the rawlog (`freeinit <input.rawlog>`): a configuration alone, or a file
  // that is neither, is told by its content.
  expectUsageError(
      "fi_one", exe, {ini},
      "freeinit: error: missing <input.rawlog>: '" + ini + "' is an INI configuration file");
  expectUsageError("fi_neither", exe, {kSrc + "/README.md"},
                   "README.md': neither an MRPT rawlog nor a ROS recording (it is a text file)");
  // A file the apps wrote is told as such, with what to give instead.
  expectUsageError("fi_truth", exe, {kSrc + "/rawlogs/stat_01.truth.csv"},
                   "stat_01.truth.csv' is the ground truth of a simulated recording "
                   "(<input>.truth.csv of freeinit-sim), not a recording: give the recording");
  expectUsageError("fi_three", exe, {ini, kRawlog, "extra"}, "'extra': unexpected argument");
  expectUsageError("fi_no_value", exe, {ini, kRawlog, "-o"}, "-o (--out): missing value");
  expectUsageError("fi_twice", exe, {ini, kRawlog, "-o", "a", "--out", "b"},
                   "-o (--out): given twice");
}

// --plugin-path: the MRPT plugin file for stock tools, on one line, exit 0, nothing else done
// (no argument needed); the same file from every app.
TEST(CommandLine, PluginPath) {
  std::vector<std::string> apps = {FREEINIT_APP, FREEINIT_SIM_APP, FREEINIT_ONLINE_APP,
                                   FREEINIT_STREAM_APP, FREEINIT_ICP_SLAM_APP};
#ifdef FREEINIT_IMPORT_BAG_APP
  apps.push_back(FREEINIT_IMPORT_BAG_APP);
#endif
  for (std::size_t i = 0; i < apps.size(); ++i) {
    SCOPED_TRACE(apps[i]);
    const Outcome r = run("plugin_path_" + std::to_string(i), apps[i], {"--plugin-path"});
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err, "");
    ASSERT_EQ(lines(r.out), 1u) << r.out;
    const std::string path = r.out.substr(0, r.out.size() - 1);
    EXPECT_TRUE(fs::is_regular_file(path)) << path;
    EXPECT_EQ(fs::canonical(path), fs::canonical(FREEINIT_PLUGIN_FILE));
    EXPECT_TRUE(r.left.empty());
  }
}

TEST(CommandLine, FreeinitSim) {
  const std::string exe = FREEINIT_SIM_APP;
  expectHelp("sim", exe, {"dyna_01", "1", "0", "<preset>.rawlog"});
  expectUsageError("sim_seed_abc", exe, {"-s", "abc", "-o", "x.rawlog"},
                   "freeinit-sim: error: -s (--seed): 'abc' is not a number");
  expectUsageError("sim_seed_fraction", exe, {"-s", "1.5"}, "-s (--seed): '1.5' is not a whole");
  expectUsageError("sim_seed_negative", exe, {"-s", "-1"},
                   "-s (--seed): -1 is out of range: accepted 0..4294967295");
  expectUsageError("sim_negative", exe, {"-d", "-1", "-n", "-5"},
                   "-d (--duration): -1 is out of range: accepted [0, 3600]");
  expectUsageError("sim_points", exe, {"-n", "-5"}, "-n (--points-per-frame): -5 is out of range");
  expectUsageError("sim_preset", exe, {"-p", "dyna_99"}, "-p (--preset): 'dyna_99' is not one of");
}

TEST(CommandLine, FreeinitStream) {
  const std::string exe = FREEINIT_STREAM_APP;
  expectHelp("stream", exe, {"47800", "127.0.0.1", "8192", "1", "none: simulate", "none"});
  expectUsageError("stream_port0", exe, {"-p", "0"}, "-p (--port): 0 is out of range");
  expectUsageError("stream_port", exe, {"-p", "70000"}, "-p (--port): 70000 is out of range");
  expectUsageError("stream_drop", exe, {"--drop", "2"},
                   "--drop: 2 is out of range: accepted [0, 1]");
  expectUsageError("stream_speed", exe, {"-x", "-1"}, "-x (--speed): -1 is out of range");
  expectUsageError("stream_mtu", exe, {"-m", "10"}, "-m (--max-datagram): 10 is out of range");
  expectUsageError("stream_restart", exe, {"--restart-at", "-5"},
                   "--restart-at: -5 is out of range");
  expectUsageError("stream_extra", exe, {"file.rawlog"}, "'file.rawlog': unexpected argument");
}

TEST(CommandLine, FreeinitOnline) {
  const std::string exe = FREEINIT_ONLINE_APP;
  expectHelp("online", exe, {"freeinit_online_out", "live.rawlog", "127.0.0.1", "47800", "2"});
  expectUsageError("online_port", exe, {"c.ini", "-p", "70000"},
                   "freeinit-online: error: -p (--port): 70000 is out of range");
  expectUsageError("online_wait", exe, {"c.ini", "-w", "-1"}, "-w (--wait): -1 is out of range");
  expectUsageError("online_idle", exe, {"c.ini", "-i", "0"},
                   "-i (--idle-timeout): 0 is out of range: accepted (0, 86400]");
  expectUsageError("online_duration", exe, {"c.ini", "-d", "abc"},
                   "-d (--max-duration): 'abc' is not a number");
  expectUsageError("online_missing", exe, {"-p", "47801"}, "missing <config.ini>");
}

TEST(CommandLine, FreeinitIcpSlam) {
  const std::string exe = FREEINIT_ICP_SLAM_APP;
  expectHelp("icp", exe, {"all", "icp_slam_out", "none"});
  expectUsageError("icp_mode", exe, {"a.ini", "b.ini", "c.rawlog", "-m", "fast"},
                   "-m (--mode): 'fast' is not one of plain | seeded | odometry | all");
  expectUsageError("icp_missing", exe, {"a.ini", "b.ini"}, "missing <input.rawlog>");
}

#ifdef FREEINIT_IMPORT_BAG_APP
TEST(CommandLine, FreeinitImportBag) {
  const std::string exe = FREEINIT_IMPORT_BAG_APP;
  expectHelp("import", exe, {"<input>.rawlog"});
  expectUsageError("import_no_config", exe, {"x.bag"}, "-c (--config): missing (required)");
  expectUsageError("import_no_bag", exe, {"-c", "x.ini"}, "missing <input>");
}
#endif

// A bad INI is found before anything is read or written: exit 1, one line naming the file, the
// line and the key, and no output folder.
TEST(CommandLine, BadIniFilesStopTheAppsBeforeAnyOutput) {
  struct Case {
    std::string name, ini, message;
  };
  const std::vector<Case> cases = {
      {"misspelt_section", "[dopler]\ndoppler_sigma = 0.05\n",
       "../bad.ini:1: [dopler]: unknown section (did you mean [doppler]?)"},
      {"duplicated_key", "[doppler]\ndoppler_sigma = 0.05\ndoppler_sigma = 0.06\n",
       "../bad.ini:3: [doppler] doppler_sigma: key given twice (first at line 2)"},
      {"huge_prior", "[imu]\ngyro_bias_sigma0 = 1e300\n",
       "../bad.ini:2: [imu] gyro_bias_sigma0: 1e300 is out of range: accepted [1e-06, 1] rad/s"},
      {"doppler_sigma", "[doppler]\ndoppler_sigma = 30\n",
       "../bad.ini:2: [doppler] doppler_sigma: 30 is out of range: accepted [1e-04, 1] m/s"},
      {"former_and_current_name",
       "[velocimeter]\ndoppler_sigma = 0.05\n[doppler]\ndoppler_sigma = 0.06\n",
       "../bad.ini:2: [velocimeter] doppler_sigma: is now [doppler] doppler_sigma, also given "
       "(line "
       "4): give it once"},
      {"variable", "[input]\nimu_label = ${FOO\n",
       "../bad.ini:2: [input] imu_label: '${FOO': variables and expressions ($...{...}) are not "
       "expanded"},
      {"window_in_samples", "[window]\nimu_samples = 500\n",
       "../bad.ini:2: [window] imu_samples: no longer a key: the window is given in seconds"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    SCOPED_TRACE(c.name);
    std::vector<std::pair<std::string, std::vector<std::string>>> apps = {
        {FREEINIT_APP, {"../bad.ini", kRawlog, "-o", "out"}}};
    if (i < 2)  // the online app loads the same way: before it listens or records
      apps.push_back({FREEINIT_ONLINE_APP, {"../bad.ini", "-o", "out", "-p", "0"}});
    for (const auto& [exe, args] : apps) {
      const Outcome r = run("ini_" + c.name, exe, args, {{"bad.ini", c.ini}});
      EXPECT_EQ(r.code, 1) << r.out << r.err;
      EXPECT_EQ(lines(r.err), 1u) << r.err;
      EXPECT_CONTAINS(r.err, ": error: " + c.message);
      EXPECT_TRUE(r.left.empty()) << r.left.front();
    }
  }
  // The rawlog and the INI swapped: the binary file is named, not printed.
  const Outcome r = run("ini_swapped", FREEINIT_APP, {kRawlog, kSrc + "/ini/freeinit.ini"});
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_CONTAINS(r.err, "stat_01.rawlog:1: binary data (byte 0x1f): not an INI text file");
  EXPECT_TRUE(r.left.empty());
}
