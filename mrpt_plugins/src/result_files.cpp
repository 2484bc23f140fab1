#include <freeinit/mrpt_plugins/map_export.h>
#include <freeinit/mrpt_plugins/output_set.h>
#include <freeinit/mrpt_plugins/output_writers.h>
#include <freeinit/mrpt_plugins/result_files.h>
#include <freeinit/mrpt_plugins/snapshots.h>

namespace freeinit::mrpt_plugins {
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

}  // namespace freeinit::mrpt_plugins
