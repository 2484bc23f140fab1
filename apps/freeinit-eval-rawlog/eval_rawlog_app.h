// `freeinit-eval-rawlog <config.ini> <a.rawlog> [b.rawlog ...]`: Free-Init and the baselines on
// recorded rawlogs with ground truth ("<name>.truth.csv" beside each, as freeinit-sim writes it),
// with the same tables and figures as freeinit-eval. Each rawlog is read with the checked reader
// (checked_recording.h: no silent truncation) and is one independent job; reading is serialized,
// the initializations run in parallel.
#pragma once

#include <freeinit/report/eval_table.h>

#include <iosfwd>
#include <string>
#include <vector>

namespace freeinit::apps {

struct EvalRawlogAppParams {
  std::string config_file;
  std::vector<std::string> rawlogs;  ///< each with "<name>.truth.csv" beside it
  std::string csv;                   ///< one row per rawlog and method ("": none)
  std::string md;                    ///< Markdown report ("": none)
  std::string plots_dir;             ///< folder for velocity_error.png ("": none)
  unsigned jobs = 0;                 ///< parallel jobs (0: hardware concurrency)
  report::FailureThresholds thresholds{0.2, 2.0};
  bool baselines = true;
  double dlio_duration = 3.0;  ///< [s] DLIO's static calibration time
  std::string command;         ///< the command line, for the Markdown header
};

class EvalRawlogApp {
 public:
  EvalRawlogAppParams params;

  /// Prints the summary table on `log`. The output files are one set each (output_set.h), all
  /// installed once every table and figure is ready; a rawlog without its truth, or that fails
  /// the reader's checks, throws (InputError / std::runtime_error naming the file) and leaves
  /// none. Returns 0.
  int run(std::ostream& log);
  /// The command line (`main` of freeinit-eval-rawlog): parses it, runs, returns the exit code.
  static int main(int argc, char** argv);

  std::vector<report::EvalRow> rows;  ///< filled by run(): per rawlog, per method
};

}  // namespace freeinit::apps
