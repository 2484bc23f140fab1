// freeinit-eval-rawlog <config.ini> <a.rawlog> [b.rawlog ...]: Free-Init and the baselines on
// recorded rawlogs with ground truth ("<name>.truth.csv" beside each, as freeinit-sim writes it),
// with the same tables and figures as freeinit-eval. Each rawlog is read with the validated
// reader (no silent truncation) and is one independent job; reading is serialized, the
// initializations run in parallel.
#include <freeinit/mrpt/app_config.h>
#include <freeinit/mrpt/ground_truth.h>
#include <freeinit/mrpt/input_validator.h>
#include <freeinit/mrpt/rawlog_reader.h>
#include <freeinit/report/eval_table.h>
#include <freeinit/report/figures.h>
#include <freeinit/report/methods.h>
#include <freeinit/report/plot.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <filesystem>
#include <iostream>
#include <mutex>
#include <stdexcept>

namespace {

namespace glue = freeinit::mrpt_glue;
namespace report = freeinit::report;
using freeinit::Vec3;

struct JobResult {
  std::vector<report::EvalRow> rows;
  std::vector<report::VelocityTrack> tracks;
};

JobResult evaluateRawlog(const glue::AppConfig& config, const std::string& rawlog,
                         const report::MethodOptions& options) {
  const std::string truth_file = glue::truthPathFor(rawlog);
  if (!std::filesystem::is_regular_file(truth_file))
    throw std::runtime_error(rawlog + ": no ground truth (expected " + truth_file + ")");
  const auto truth = glue::readTruthCsv(truth_file);
  // Reading is one job at a time: MRPT does not document its class registry and deserialization
  // as thread-safe. The initializations then run in parallel on plain data.
  static std::mutex mrpt_mutex;
  glue::ValidatedInput in;
  {
    const std::lock_guard<std::mutex> lock(mrpt_mutex);
    in = glue::readRecording(rawlog, config);
  }
  const freeinit::Extrinsics extrinsics =
      config.extrinsics.from_sensor_pose && in.sensor_pose_extrinsics ? *in.sensor_pose_extrinsics
                                                                      : config.core.extrinsics;
  const auto runs = report::runMethods(config.core, in.imu, in.frames, extrinsics, options);

  // No point labels in a rawlog: the rows have the errors and the NEES, no bound.
  const report::TruthFn at = [&](double t) {
    const auto s = glue::truthAt(truth, t);
    if (!s) throw std::runtime_error(truth_file + ": does not cover t = " + std::to_string(t));
    return *s;
  };
  JobResult out;
  for (const auto& m : runs) out.rows.push_back(report::makeEvalRow(rawlog, 0, m, at));
  out.tracks =
      report::velocityTracks(runs, in.imu.front().t, [&](double t) -> Vec3 { return at(t).v_b(); });
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    TCLAP::CmdLine cmd(
        "freeinit-eval-rawlog: Free-Init and the baseline initializers on rawlogs with ground "
        "truth (<name>.truth.csv beside each), as Markdown/CSV tables and figures",
        ' ', "0.1");
    TCLAP::UnlabeledValueArg<std::string> ini("config", "INI configuration file", true, "",
                                              "config.ini", cmd);
    TCLAP::UnlabeledMultiArg<std::string> rawlogs("rawlogs", "input rawlogs", true, "a.rawlog",
                                                  cmd);
    TCLAP::ValueArg<std::string> md("", "md", "Markdown report", false, "", "FILE", cmd);
    TCLAP::ValueArg<std::string> csv("", "csv", "CSV, one row per rawlog and method", false, "",
                                     "FILE", cmd);
    TCLAP::ValueArg<std::string> plots("", "plots", "folder for velocity_error.png", false, "",
                                       "DIR", cmd);
    TCLAP::ValueArg<unsigned> jobs("j", "jobs", "parallel jobs (0: hardware concurrency)", false, 0,
                                   "N", cmd);
    TCLAP::ValueArg<double> fail_v("", "fail-velocity", "failure above this velocity error [m/s]",
                                   false, 0.2, "V", cmd);
    TCLAP::ValueArg<double> fail_g("", "fail-gravity", "failure above this gravity error [deg]",
                                   false, 2.0, "D", cmd);
    TCLAP::ValueArg<double> dlio("", "dlio-duration", "DLIO's static calibration time [s]", false,
                                 3.0, "S", cmd);
    TCLAP::SwitchArg no_baselines("", "no-baselines", "Free-Init only", cmd);
    cmd.parse(argc, argv);

    std::string command = "freeinit-eval-rawlog";
    for (int i = 1; i < argc; ++i) command += std::string(" ") + argv[i];
    const glue::AppConfig config = glue::loadAppConfig(ini.getValue());
    report::MethodOptions options;
    options.baselines = !no_baselines.getValue();
    options.dlio_duration = dlio.getValue();
    const report::FailureThresholds thresholds{fail_v.getValue(), fail_g.getValue()};

    const auto& files = rawlogs.getValue();
    std::vector<JobResult> results(files.size());
    report::parallelFor(files.size(), jobs.getValue(), [&](std::size_t i) {
      results[i] = evaluateRawlog(config, files[i], options);
    });
    std::vector<report::EvalRow> rows;
    for (const auto& r : results) rows.insert(rows.end(), r.rows.begin(), r.rows.end());
    report::markFailures(rows, thresholds);
    std::cout << report::markdownSummary(rows, thresholds);
    if (!csv.getValue().empty()) report::writeEvalCsv(csv.getValue(), rows);
    if (!md.getValue().empty()) report::writeEvalMarkdown(md.getValue(), rows, thresholds, command);
    if (!plots.getValue().empty()) {
      std::filesystem::create_directories(plots.getValue());
      std::vector<cv::Mat> panels;
      for (std::size_t i = 0; i < files.size(); ++i)
        panels.push_back(report::velocityErrorPanel(std::filesystem::path(files[i]).filename(),
                                                    results[i].tracks, 640, 400));
      const auto png = (std::filesystem::path(plots.getValue()) / "velocity_error.png").string();
      report::savePng(png, report::tile(panels, panels.size() >= 2 ? 2 : 1));
      std::cout << "wrote " << png << "\n";
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "freeinit-eval-rawlog: error: " << e.what() << "\n";
    return 1;
  }
}
