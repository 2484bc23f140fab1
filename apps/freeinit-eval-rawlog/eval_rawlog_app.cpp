#include "eval_rawlog_app.h"

#include <freeinit/app_support/app_config.h>
#include <freeinit/app_support/checked_recording.h>
#include <freeinit/app_support/command_line.h>
#include <freeinit/app_support/ground_truth.h>
#include <freeinit/app_support/output_set.h>
#include <freeinit/app_support/stop_signal.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <freeinit/report/figures.h>
#include <freeinit/report/methods.h>
#include <freeinit/report/plot.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <mutex>
#include <stdexcept>

namespace freeinit::apps {
namespace {

constexpr const char* kPlotFile = "velocity_error.png";

struct JobResult {
  std::vector<report::EvalRow> rows;
  std::vector<report::VelocityTrack> tracks;
};

JobResult evaluateRawlog(const app_support::AppConfig& config, const std::string& rawlog,
                         const report::MethodOptions& options) {
  const std::string truth_file = app_support::truthPathFor(rawlog);
  if (!std::filesystem::is_regular_file(truth_file))
    throw std::runtime_error(rawlog + ": no ground truth (expected " + truth_file + ")");
  const auto truth = app_support::readTruthCsv(truth_file);
  // Reading is one job at a time: MRPT does not document its class registry and deserialization
  // as thread-safe. The initializations then run in parallel on plain data.
  static std::mutex mrpt_mutex;
  app_support::CheckedRecording in;
  {
    const std::lock_guard<std::mutex> lock(mrpt_mutex);
    in = app_support::readRecording(rawlog, config);
  }
  const Extrinsics extrinsics = config.extrinsics.from_sensor_pose && in.sensor_pose_extrinsics
                                    ? *in.sensor_pose_extrinsics
                                    : config.core.extrinsics;
  const auto runs = report::runMethods(config.core, in.imu, in.frames, extrinsics, options);

  // No point labels in a rawlog: the rows have the errors and the NEES, no bound.
  const report::TruthFn at = [&](double t) {
    const auto s = app_support::truthAt(truth, t);
    if (!s) throw std::runtime_error(truth_file + ": does not cover t = " + std::to_string(t));
    return *s;
  };
  JobResult out;
  for (const auto& m : runs) out.rows.push_back(report::makeEvalRow(rawlog, 0, m, at));
  out.tracks =
      report::velocityTracks(runs, in.imu.front().t, [&](double t) -> Vec3 { return at(t).v_b(); });
  return out;
}

/// One output file of the run, as a set of its own (output_set.h): locked now, installed last.
std::unique_ptr<app_support::OutputSet> fileSet(const std::string& file, std::ostream& log) {
  if (file.empty()) return nullptr;
  const std::filesystem::path p(file);
  const std::string name = p.filename().string();
  if (name.empty() || std::filesystem::is_directory(p))
    throw std::invalid_argument(file + ": a file name is needed (this is a folder)");
  app_support::OutputSetOptions options;
  options.owned = {name};
  return std::make_unique<app_support::OutputSet>(p.parent_path().string(), name, options, log);
}

}  // namespace

int EvalRawlogApp::run(std::ostream& log) {
  // Each output is a set of its own (its staging beside it), all installed once every table and
  // figure is ready.
  auto csv_set = fileSet(params.csv, log);
  auto md_set = fileSet(params.md, log);
  std::unique_ptr<app_support::OutputSet> plots_set;
  if (!params.plots_dir.empty()) {
    app_support::OutputSetOptions options;
    options.owned = {kPlotFile};
    plots_set =
        std::make_unique<app_support::OutputSet>(params.plots_dir, "velocity_error", options, log);
  }
  std::vector<std::string> notices;  // keys given under their former names
  const app_support::AppConfig config = app_support::loadAppConfig(params.config_file, &notices);
  for (const std::string& n : notices) log << n << "\n";
  report::MethodOptions options;
  options.baselines = params.baselines;
  options.dlio_duration = params.dlio_duration;

  const auto& files = params.rawlogs;
  std::vector<JobResult> results(files.size());
  report::parallelFor(files.size(), params.jobs, [&](std::size_t i) {
    app_support::throwIfStopRequested();
    results[i] = evaluateRawlog(config, files[i], options);
  });
  app_support::throwIfStopRequested();
  rows.clear();
  for (const auto& r : results) rows.insert(rows.end(), r.rows.begin(), r.rows.end());
  report::markFailures(rows, params.thresholds);
  log << report::markdownSummary(rows, params.thresholds);
  if (csv_set)
    csv_set->write(std::filesystem::path(params.csv).filename().string(),
                   [&](const std::string& p) { report::writeEvalCsv(p, rows); });
  if (md_set)
    md_set->write(std::filesystem::path(params.md).filename().string(), [&](const std::string& p) {
      report::writeEvalMarkdown(p, rows, params.thresholds, params.command);
    });
  if (plots_set) {
    std::vector<cv::Mat> panels;
    for (std::size_t i = 0; i < files.size(); ++i)
      panels.push_back(report::velocityErrorPanel(std::filesystem::path(files[i]).filename(),
                                                  results[i].tracks, 640, 400));
    plots_set->write(kPlotFile, [&](const std::string& p) {
      report::savePng(p, report::tile(panels, panels.size() >= 2 ? 2 : 1));
    });
  }
  for (auto* set : {csv_set.get(), md_set.get(), plots_set.get()})
    if (set) set->commit();
  if (plots_set) log << "wrote " << plots_set->finalPath(kPlotFile) << "\n";
  return 0;
}

int EvalRawlogApp::main(int argc, char** argv) {
  namespace range = freeinit::config;
  app_support::CommandLine cli(
      "freeinit-eval-rawlog",
      "Free-Init and the baseline initializers on rawlogs with ground truth "
      "(<name>.truth.csv beside each), as Markdown/CSV tables and figures");
  const auto& ini = cli.positional("config.ini", "INI configuration file (ini/freeinit.ini)");
  const auto& rawlogs = cli.positionals("input.rawlog", "input rawlogs, each with its truth");
  const auto& md = cli.text("", "md", "Markdown report", "", "FILE", "none");
  const auto& csv = cli.text("", "csv", "CSV, one row per rawlog and method", "", "FILE", "none");
  const auto& plots = cli.text("", "plots", "folder for velocity_error.png", "", "DIR", "none");
  const auto& jobs =
      cli.integer("j", "jobs", "parallel jobs (0: hardware concurrency)", 0, 0, 1024, "N");
  const auto& fail_v = cli.number("", "fail-velocity", "failure above this velocity error [m/s]",
                                  0.2, range::aboveUpTo(0, 1e3), "V");
  const auto& fail_g = cli.number("", "fail-gravity", "failure above this gravity error [deg]", 2.0,
                                  range::aboveUpTo(0, 180), "D");
  const auto& dlio = cli.number("", "dlio-duration", "DLIO's static calibration time [s]", 3.0,
                                range::aboveUpTo(0, 3600), "S");
  const auto& no_baselines = cli.flag("", "no-baselines", "Free-Init only");
  if (const auto code = cli.parse(argc, argv)) return *code;
  return app_support::runMain(cli.program(), [&] {
    EvalRawlogApp app;
    auto& p = app.params;
    p.config_file = ini.value;
    p.rawlogs = rawlogs.value;
    p.csv = csv.value;
    p.md = md.value;
    p.plots_dir = plots.value;
    p.jobs = static_cast<unsigned>(jobs.value);
    p.thresholds = {fail_v.value, fail_g.value};
    p.baselines = !no_baselines.value;
    p.dlio_duration = dlio.value;
    p.command = "freeinit-eval-rawlog";
    for (int i = 1; i < argc; ++i) p.command += std::string(" ") + argv[i];
    return app.run(std::cout);
  });
}

}  // namespace freeinit::apps
