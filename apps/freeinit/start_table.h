// The table of initializations at several starts of one recording (freeinit --every / --starts):
// one row per start with its status, state, sigmas and, with ground truth, errors and NEES; as
// CSV, Markdown and a PNG of errors (or sigmas) over time.
#pragma once

#include <freeinit/app_support/ground_truth.h>
#include <freeinit/app_support/ingest.h>
#include <freeinit/initial_state.h>

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace freeinit::apps {

/// Errors of a state against the truth at its timestamp with their normalized estimation errors
/// squared from the state's covariance (first order): body velocity (3 dof), tilt (the gravity
/// direction in the body frame, 2 dof), gyro bias (3), accelerometer bias (3).
struct StateNees {
  app_support::TruthErrors errors;
  double vel_b = 0, tilt = 0, gyro_bias = 0, accel_bias = 0;
};
/// Throws std::runtime_error if the truth does not cover the state's time.
StateNees stateNees(const InitialState& s, const std::vector<app_support::TruthSample>& truth);

struct StartRow {
  std::size_t index = 0;
  double start = 0;                   ///< [UNIX s] the requested start
  double start_offset = 0;            ///< [s] after the first record
  std::string folder;                 ///< output folder relative to --out ("" if it has none)
  std::string status;                 ///< the InitStatus, "input_error" or "unreadable"
  std::string message;                ///< why, when not ok
  std::optional<InitialState> state;  ///< when the estimator ran
  double window_begin = 0;            ///< [UNIX s] first sample of the window (when ok)
  std::optional<StateNees> truth;     ///< when ok and ground truth is beside the rawlog
};

/// "start_0012.300" for 12.3 s after the first record (sortable by name).
std::string startFolderName(double offset);

/// The row of start `index` at `start` [UNIX s] (`first` [UNIX s]: the first record's stamp)
/// whose session `s` closed: input_error if it failed; not_enough_data without outputs when the
/// recording ends before its window closes (`at_end`: the file ended with the session open); else
/// its state (with `truth` beside the rawlog, errors and NEES), and `folder` names where its
/// outputs go (startFolderName).
StartRow startRow(std::size_t index, double start, double first, const app_support::InitSession& s,
                  bool at_end, const std::vector<app_support::TruthSample>& truth);
/// The row of a start the reading did not reach: not_enough_data (no record at or after it), or
/// "unreadable" with `read_error`, the reader's error that ended the reading.
StartRow unreachedStartRow(std::size_t index, double start, double first,
                           const std::optional<std::string>& read_error);
/// A start that did not initialize, unless the file ended before its window closed (`at_end`).
bool startFailed(const StartRow& row, bool at_end);
/// The row as one line on the log: "Start 3 at 12.000 s: ok, |v_b| ..., errors: ... -> <folder>",
/// the folder under `out_dir`.
void printStartRow(std::ostream& log, const StartRow& row, const std::string& out_dir);

void writeStartTableCsv(const std::string& path, const std::vector<StartRow>& rows);
void writeStartTableMarkdown(const std::string& path, const std::vector<StartRow>& rows,
                             const std::string& rawlog, const std::string& command);
/// Errors (with ground truth) and 1-sigma of velocity, tilt, gyro and accelerometer bias against
/// the start offset, four panels. Written atomically.
void renderStartPlot(const std::string& png, const std::vector<StartRow>& rows, int width,
                     int height);

}  // namespace freeinit::apps
