// The main application: `freeinit [<config.ini>] <input.rawlog> [--out DIR]`. Streams the rawlog
// through the ingest path (ingest.h) into the estimator and stops reading once the state is
// ready; writes the outputs (each complete or absent) and compares with the ground truth when
// "<input>.truth.csv" sits beside the rawlog.
//
// Anywhere in a recording: `--start T` initializes with the records from T on (T in seconds after
// the first record, or a UNIX stamp when T > 1e8), seeking with the rawlog's index (rawlog_index.h)
// instead of reading what comes before. `--every S` / `--starts FILE` initialize at many starts in
// one pass, several estimators side by side when windows overlap: each start's outputs go to its
// own folder, with one table of all starts (starts.csv, starts.md) and a plot (starts.png).
//
// Without a configuration file the defaults apply (those ini/freeinit.ini documents: extrinsics
// from the observations' sensorPose). Whatever the mode, the outputs are one set (output_set.h):
// staged while the run goes on and installed as a whole when it is complete, replacing the earlier
// run's in --out; without --out, `freeinit <input.rawlog>` writes a new folder every run
// (freeinit_out/<input>.<time>/), so that no earlier result is replaced.
#pragma once

#include <freeinit/app_support/app_config.h>
#include <freeinit/app_support/ground_truth.h>
#include <freeinit/initial_state.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "start_plan.h"
#include "start_table.h"

namespace freeinit::apps {

/// The output folder of `freeinit <config.ini> <input.rawlog>` without --out.
inline constexpr const char* kDefaultOutDir = "freeinit_out";

/// A new output folder for `rawlog` under `root`, created empty (so that no other run takes it):
/// <root>/<rawlog's name without extension>.<local time YYYYmmdd-HHMMSS>, with -2, -3, ...
/// appended when a folder of that name exists. Throws OutputError when it cannot be created.
std::string createNewOutputFolder(const std::string& root, const std::string& rawlog);

struct FreeInitAppParams {
  std::string config_file;  ///< "" for the defaults (those ini/freeinit.ini documents)
  std::string rawlog;
  /// --out; "": a new folder under new_out_root (createNewOutputFolder), never an earlier one.
  std::string out_dir = kDefaultOutDir;
  std::string new_out_root = kDefaultOutDir;  ///< where out_dir = "" makes its folder
  bool progress = true;                       ///< progress bars on the log stream
  /// The effective configuration on the log stream too (it is always written to
  /// effective_config.ini in the outputs).
  bool echo_config = true;
  bool progress_terminal = false;  ///< the log is a terminal: redraw the bars in place
  std::optional<double> start;     ///< --start (see kUnixStampThreshold)
  double every = 0;                ///< --every [s] (> 0: repeated starts from `start` or 0)
  std::string starts_file;         ///< --starts FILE
  bool check_all = false;          ///< --check-all: read and check the whole file
  bool salvage = false;  ///< --salvage: a file cut short is read up to its last whole record
  mrpt_plugins::RawlogIndexPolicy index;  ///< --no-index: use = false
  std::string command;                    ///< the command line, for the table's header

  /// `freeinit <input.rawlog>` (config_file ""): one line naming the file when, by its content
  /// (file_kind.h), it is no rawlog (a configuration given alone, a ROS1 bag, a file that is
  /// neither), else "". With a configuration file "": its reader and the rawlog's check both,
  /// as they always have (a swapped pair: the INI reader names the binary file). A file that
  /// cannot be read passes: its reader says why.
  std::string argumentsProblem() const;
};

class FreeInitApp {
 public:
  FreeInitAppParams params;

  /// Runs the whole job. The outputs are one set (output_set.h): staged, installed at the end;
  /// bad input or configuration throws (InputError / std::invalid_argument, also for an
  /// argumentsProblem()), a stop request Interrupted, and --out then holds no output of ours (a
  /// new folder is removed). Returns the process exit code: 0 initialized, 3 not
  /// initialized (the reason is in initial_state.ini); with several starts 0 if every start
  /// whose window the recording covers initialized, else 3 (the table says why; starts the
  /// recording ends too early for are listed as not_enough_data).
  int run(std::ostream& log);
  /// The command line (`main` of freeinit): parses it, runs, returns the exit code.
  static int main(int argc, char** argv);

  // Filled by run(), for callers and tests.
  std::string out_dir;  ///< where the outputs went (params.out_dir, or the new folder)
  app_support::AppConfig config;
  InitResult result;  ///< one start
  std::optional<app_support::TruthErrors> errors_wrt_gt;
  std::vector<StartRow> rows;         ///< several starts
  std::vector<std::string> warnings;  ///< as logged
  std::size_t records_read = 0;       ///< records deserialized
  bool read_to_end = false;           ///< the whole file was read (and checked)
  std::string salvage_stop;           ///< --salvage: where a cut file stopped ("" if whole)
  bool index_used = false;            ///< the rawlog's index was found and used
  std::string index_written;          ///< where the index was written ("" if not)

 private:
  struct Job;       // what the steps of one run share (free_init_app.cpp)
  class StartPass;  // the pass over the records for the run's starts (free_init_app.cpp)

  /// The configuration (the defaults without a file) into `config`, echoed; returns its text.
  std::string loadConfiguration(std::ostream& log);
  /// Opens the rawlog and plans the starts; reads the ground truth beside it.
  void openRecording(Job& job, std::ostream& log);
  /// One start: its window through the ingest path, the state, its outputs.
  int initializeOnce(Job& job, std::ostream& log);
  /// --every / --starts: every start's window in one pass, the table of them.
  int initializeAtStarts(Job& job, std::ostream& log);
  void writeStartTable(Job& job, std::ostream& log);
  /// Logs a warning and keeps it in `warnings`.
  void warn(std::ostream& log, const std::string& warning);
};

}  // namespace freeinit::apps
