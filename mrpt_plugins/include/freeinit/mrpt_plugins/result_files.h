// The files of one initialization's result besides initial_state.ini, as one table that the apps
// write from, the [output] section declares its flags from and the output folder's list of owned
// names (output_set.h) includes. A new output is its writer and one row in result_files.cpp (and,
// for a new flag, one bool in OutputParams).
#pragma once

#include <freeinit/initial_state.h>
#include <freeinit/mrpt_plugins/app_config.h>
#include <freeinit/mrpt_plugins/ground_truth.h>

#include <string>
#include <vector>

namespace freeinit::mrpt_plugins {

class OutputSet;

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

/// Stages the result files [output] enables in `set`, under `prefix` ("" or "start_0012.000/").
/// `truth` may be empty.
void writeResultFiles(OutputSet& set, const std::string& prefix, const OutputParams& output,
                      const InitResult& result, const std::vector<TruthSample>& truth);

}  // namespace freeinit::mrpt_plugins
