// The files of one initialization's result besides initial_state.ini, as one table that the apps
// write from, the [output] section declares its flags from and the output folder's list of owned
// names (output_set.h) includes. A new output is its writer and one row in result_files.cpp (and,
// for a new flag, one bool in OutputParams).
#pragma once

#include <freeinit/app_support/ground_truth.h>
#include <freeinit/initial_state.h>
#include <freeinit/io/config_section.h>

#include <string>
#include <vector>

namespace freeinit::app_support {

class OutputSet;
struct OutputSetOptions;

/// What the app writes to its output folder. INI section [output].
struct OutputParams {
  bool simplemap = true;      ///< static_map.simplemap (stock MRPT classes only)
  bool ply = true;            ///< static_map.ply
  bool trajectory = true;     ///< trajectory_tum.txt
  bool velocities = true;     ///< velocimeter.csv
  bool snapshots = true;      ///< PNGs rendered offscreen
  int snapshot_width = 1280;  ///< [px]
  int snapshot_height = 800;  ///< [px]
};

/// [output]: one flag per result file (from the table below) and the snapshots' size.
const config::Section<OutputParams>& outputSection();

/// What a result file is written from.
struct ResultInputs {
  const InitResult& result;
  const std::vector<TruthSample>& truth;  ///< may be empty
  const OutputParams& output;
};

struct ResultFile {
  const char* name;             ///< in the output folder (or a start's folder)
  const char* key;              ///< the [output] flag that enables it
  bool OutputParams::*enabled;  ///< that flag in OutputParams
  const char* help;             ///< the flag's help; nullptr: a row above with the key has it
  bool (*has_content)(const InitResult&);  ///< written only when true; nullptr: always
  void (*write)(const std::string& path, const ResultInputs& in);
};

/// Every result file, in the order they are written and their flags are declared.
const std::vector<ResultFile>& resultFiles();

/// Names of every file writeResultFiles may write (whatever [output] enables).
std::vector<std::string> resultFileNames();

/// Every name an app of this project writes into an output folder (freeinit, freeinit-online,
/// freeinit-icp-slam and its export, freeinit-eval-rawlog's plots), the result files included:
/// what a folder set owns, so that one app's set replaces another's as a whole.
std::vector<std::string> folderOutputNames();
/// The options of a folder set (folderOutputNames()), with initial_state.ini installed last and
/// freeinit-online's recording ("live.rawlog") and its statistics ("stream_stats.ini") kept as a
/// pair, renamed with their time, whichever app replaces the set.
OutputSetOptions folderSetOptions();

/// Stages the result files [output] enables in `set`, under `prefix` ("" or "start_0012.000/").
/// `truth` may be empty.
void writeResultFiles(OutputSet& set, const std::string& prefix, const OutputParams& output,
                      const InitResult& result, const std::vector<TruthSample>& truth);

}  // namespace freeinit::app_support
