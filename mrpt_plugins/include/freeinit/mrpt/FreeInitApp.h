// The main application: `freeinit <config.ini> <input.rawlog> [--out DIR]`. Reads and validates the
// rawlog, runs the observation handler, writes the outputs (each complete or absent) and compares
// with the ground truth when "<input>.truth.csv" sits beside the rawlog.
#pragma once

#include <freeinit/initial_state.h>
#include <freeinit/mrpt/app_config.h>
#include <freeinit/mrpt/ground_truth.h>

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace freeinit::mrpt_glue {

struct FreeInitAppParams {
  std::string config_file;
  std::string rawlog;
  std::string out_dir = "freeinit_out";
  bool progress = true;            ///< progress bars on the log stream
  bool progress_terminal = false;  ///< the log is a terminal: redraw the bars in place
};

/// Names of every file writeResultFiles may write (whatever [output] enables).
std::vector<std::string> resultFileNames();

/// Writes the [output] files other than initial_state.ini (static map .simplemap / .ply,
/// trajectory, velocimeter CSV, snapshots) into `out_dir`, each atomically. `truth` may be empty.
void writeResultFiles(const std::string& out_dir, const OutputParams& output,
                      const InitResult& result, const std::vector<TruthSample>& truth);

class FreeInitApp {
 public:
  FreeInitAppParams params;

  /// Runs the whole job. Bad input or configuration throws (InputError / std::invalid_argument)
  /// before any output is written. Returns the process exit code: 0 initialized, 3 not
  /// initialized (the reason is in initial_state.ini).
  int run(std::ostream& log);

  // Filled by run(), for callers and tests.
  AppConfig config;
  InitResult result;
  std::optional<TruthErrors> errors_wrt_gt;
};

}  // namespace freeinit::mrpt_glue
