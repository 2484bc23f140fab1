#include <freeinit/app_support/map_export.h>
#include <freeinit/app_support/output_set.h>
#include <freeinit/app_support/output_writers.h>
#include <freeinit/app_support/result_files.h>
#include <freeinit/app_support/snapshots.h>

namespace freeinit::app_support {

const config::Section<OutputParams>& outputSection() {
  using P = OutputParams;
  static const auto s = [] {
    config::Section<P> sec("output", "what the app writes to its output folder");
    for (const ResultFile& f : resultFiles())  // one flag per key, from its first file
      if (f.help != nullptr) sec.flag(f.key, f.enabled, f.help);
    sec.number("snapshot_width", &P::snapshot_width, "px", config::between(64, 16384),
               "snapshot width")
        .number("snapshot_height", &P::snapshot_height, "px", config::between(64, 16384),
                "snapshot height");
    return sec;
  }();
  return s;
}

std::vector<std::string> folderOutputNames() {
  std::vector<std::string> names = {
      // freeinit (one start, and several: start folders and their table)
      "initial_state.ini", "effective_config.ini", "errors_wrt_gt.ini", "starts.csv", "starts.md",
      "starts.png", "start_*/",
      // freeinit-online
      "stream_stats.ini",
      // freeinit-icp-slam, its export and freeinit-eval-rawlog --plots
      "icp_slam_seed.ini", "odometry_alone_tum.txt", "results.txt", "trajectories.png", "plain/",
      "seeded/", "odometry/", "plain.rawlog", "plain.ini", "seeded.rawlog", "seeded.ini",
      "odometry.rawlog", "odometry.ini", "velocity_error.png"};
  for (std::string& n : resultFileNames()) names.push_back(std::move(n));  // and the results'
  return names;
}

OutputSetOptions folderSetOptions() {
  OutputSetOptions o;
  o.owned = folderOutputNames();
  o.install_last = {"initial_state.ini", "starts.csv", "starts.md"};
  // freeinit-online's recording and its statistics, kept as a pair by whichever app replaces the
  // set (freeinit --out on a live run's folder renames them as freeinit-online does).
  o.recording = "live.rawlog";
  o.recording_companion = "stream_stats.ini";
  return o;
}

namespace {

bool hasMap(const InitResult& r) { return !r.static_map.empty(); }
bool hasVelocities(const InitResult& r) { return !r.velocities.empty(); }

}  // namespace

const std::vector<ResultFile>& resultFiles() {
  using P = OutputParams;
  using In = ResultInputs;
  static const std::vector<ResultFile> files = {
      {"static_map.simplemap", "simplemap", &P::simplemap,
       "static_map.simplemap (stock MRPT classes)", nullptr,
       [](const std::string& p, const In& in) { writeStaticSimplemap(p, in.result); }},
      {"static_map.ply", "ply", &P::ply, "static_map.ply", nullptr,
       [](const std::string& p, const In& in) { writePly(p, in.result.static_map); }},
      {"trajectory_tum.txt", "trajectory", &P::trajectory, "trajectory_tum.txt", nullptr,
       [](const std::string& p, const In& in) { writeTum(p, in.result.trajectory); }},
      {"velocimeter.csv", "velocities", &P::velocities, "velocimeter.csv", nullptr,
       [](const std::string& p, const In& in) { writeVelocityCsv(p, in.result.velocities); }},
      {"static_map.png", "snapshots", &P::snapshots, "PNG snapshots rendered offscreen", hasMap,
       [](const std::string& p, const In& in) {
         renderMapSnapshot(p, in.result, in.output.snapshot_width, in.output.snapshot_height);
       }},
      {"velocity.png", "snapshots", &P::snapshots, nullptr, hasVelocities,
       [](const std::string& p, const In& in) {
         renderVelocityPlot(p, in.result, in.truth, in.output.snapshot_width,
                            in.output.snapshot_height);
       }},
  };
  return files;
}

std::vector<std::string> resultFileNames() {
  std::vector<std::string> names;
  for (const ResultFile& f : resultFiles()) names.emplace_back(f.name);
  return names;
}

void writeResultFiles(OutputSet& set, const std::string& prefix, const OutputParams& output,
                      const InitResult& result, const std::vector<TruthSample>& truth) {
  const ResultInputs in{result, truth, output};
  for (const ResultFile& f : resultFiles()) {
    if (!(output.*f.enabled) || (f.has_content && !f.has_content(result))) continue;
    set.write(prefix + f.name, [&](const std::string& p) { f.write(p, in); });
  }
}

}  // namespace freeinit::app_support
