// freeinit-eval: Free-Init and the baseline initializers (FAST-LIO2 and DLIO static means,
// per-frame Doppler least squares) on simulated presets x seeds, against the ground truth.
// Jobs (one per preset and seed) are independent and deterministic and run in parallel; the
// tables are the same whatever --jobs (only the wall times differ).
#include <freeinit/report/eval_table.h>
#include <freeinit/report/figures.h>
#include <freeinit/report/methods.h>
#include <freeinit/report/plot.h>
#include <freeinit/sim/evaluation.h>
#include <freeinit/sim/presets.h>
#include <freeinit/sim/simulator.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <functional>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using freeinit::Vec3;
namespace report = freeinit::report;
namespace sim = freeinit::sim;

const char* const kUsage =
    "Usage: freeinit-eval [options] [preset ...]   (default: every preset)\n"
    "  --seeds N            seeds 1..N per preset (3)\n"
    "  --jobs N             parallel jobs (0: hardware concurrency, the default)\n"
    "  --md FILE            Markdown report (paper Table I/II layout plus every run)\n"
    "  --csv FILE           CSV, one row per preset, seed and method\n"
    "  --plots DIR          velocity_error_dyna.png and tunnel_velocity.png (first seed)\n"
    "  --fail-velocity V    a run fails above this velocity error [m/s] (0.2)\n"
    "  --fail-gravity D     a run fails above this gravity error [deg] (2)\n"
    "  --duration S         simulated seconds (3.2: DLIO's 3 s calibration; 1.2 with\n"
    "                       --no-baselines)\n"
    "  --points P           points per frame (preset: 60000)\n"
    "  --stride K           velocimeter point stride (configuration default)\n"
    "  --no-baselines       Free-Init only\n"
    "  --dlio-duration S    DLIO's static calibration time (3)\n"
    "  --gyro-prior SIGMA   gyro-bias prior: the truth plus noise of this std [rad/s]\n"
    "  --passes N, --seed-samples N, --tau S, --no-gyro-bias-estimate, --zero-gyro-bias:\n"
    "                       estimator variants\n"
    "  --trace              print Free-Init's velocity errors over the window\n"
    "  -q                   no per-run lines\n";

struct Options {
  int seeds = 3;
  unsigned jobs = 0;
  std::string md, csv, plots;
  report::FailureThresholds thresholds;
  double duration = -1;  // < 0: default by baselines
  int points = 0, stride = 0, passes = -1, seed_samples = -1;
  double tau = -1, gyro_prior = 0;
  bool zero_bg = false, no_db = false, trace = false, quiet = false;
  report::MethodOptions methods;
  std::vector<std::string> presets;
  std::string command;
};

Options parse(int argc, char** argv) {
  Options o;
  o.command = "freeinit-eval";
  for (int i = 1; i < argc; ++i) o.command += std::string(" ") + argv[i];
  auto value = [&](int& i) -> std::string {
    if (i + 1 >= argc) throw std::invalid_argument(std::string(argv[i]) + " needs a value");
    return argv[++i];
  };
  auto number = [&](int& i) {
    const std::string flag = argv[i], v = value(i);
    const auto x = report::parseDouble(v);
    if (!x) throw std::invalid_argument(flag + ": not a number: '" + v + "'");
    return *x;
  };
  // A whole number in [lo, hi]: a fraction or an out-of-range value is an error, not rounded
  // (checked on the double, before any conversion).
  auto integer = [&](int& i, int lo, int hi) {
    const std::string flag = argv[i];
    const double x = number(i);
    if (!(x >= lo && x <= hi) || x != std::floor(x))
      throw std::invalid_argument(flag + ": must be a whole number in [" + std::to_string(lo) +
                                  ", " + std::to_string(hi) + "], not '" + argv[i] + "'");
    return static_cast<int>(x);
  };
  const std::map<std::string, std::function<void(int&)>> with_value = {
      {"--seeds", [&](int& i) { o.seeds = integer(i, 1, 100000); }},
      {"--jobs", [&](int& i) { o.jobs = static_cast<unsigned>(integer(i, 0, 1024)); }},
      {"--md", [&](int& i) { o.md = value(i); }},
      {"--csv", [&](int& i) { o.csv = value(i); }},
      {"--plots", [&](int& i) { o.plots = value(i); }},
      {"--fail-velocity", [&](int& i) { o.thresholds.velocity = number(i); }},
      {"--fail-gravity", [&](int& i) { o.thresholds.gravity_deg = number(i); }},
      {"--duration", [&](int& i) { o.duration = number(i); }},
      {"--points", [&](int& i) { o.points = integer(i, 1, 100000000); }},
      {"--stride", [&](int& i) { o.stride = integer(i, 1, 1000000); }},
      {"--dlio-duration", [&](int& i) { o.methods.dlio_duration = number(i); }},
      {"--gyro-prior", [&](int& i) { o.gyro_prior = number(i); }},
      {"--passes", [&](int& i) { o.passes = integer(i, 0, 1000); }},
      {"--seed-samples", [&](int& i) { o.seed_samples = integer(i, 0, 1000000); }},
      {"--tau", [&](int& i) { o.tau = number(i); }},
  };
  const std::map<std::string, bool*> switches = {{"--no-gyro-bias-estimate", &o.no_db},
                                                 {"--zero-gyro-bias", &o.zero_bg},
                                                 {"--trace", &o.trace},
                                                 {"-q", &o.quiet}};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    }
    if (const auto f = with_value.find(a); f != with_value.end()) {
      f->second(i);
    } else if (const auto sw = switches.find(a); sw != switches.end()) {
      *sw->second = true;
    } else if (a == "--no-baselines") {
      o.methods.baselines = false;
    } else if (!a.empty() && a[0] == '-') {
      throw std::invalid_argument("unknown option " + a);
    } else {
      o.presets.push_back(a);
    }
  }
  if (o.duration < 0) o.duration = o.methods.baselines ? o.methods.dlio_duration + 0.2 : 1.2;
  if (o.presets.empty()) o.presets = sim::presetNames();
  for (const auto& p : o.presets) sim::presetInfo(p);  // throws on an unknown name
  return o;
}

struct JobResult {
  std::vector<report::EvalRow> rows;
  std::vector<report::VelocityTrack> tracks;
  std::string log;
};

template <typename... Args>
void appendf(std::string& s, const char* fmt, Args... args) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), fmt, args...);
  s += buf;
}

JobResult runJob(const Options& o, const std::string& name, int seed) {
  auto sc = sim::preset(name, static_cast<std::uint64_t>(seed));
  sc.duration = o.duration;
  if (o.points > 0) sc.points_per_frame = o.points;
  if (o.zero_bg) {
    sc.random_biases = false;
    sc.b_g.setZero();
    sc.b_a = Vec3(0.1, -0.08, 0.05);
  }
  const auto rec = sim::simulate(sc);
  freeinit::FreeInitConfig cfg;
  if (o.stride > 0) cfg.velocimeter.point_stride = o.stride;
  if (o.passes >= 0) cfg.window.refinement_passes = o.passes;
  if (o.seed_samples >= 0) cfg.window.seed_duration = o.seed_samples / sc.imu_rate;
  if (o.tau >= 0) cfg.gravity.velocity_error_correlation_time = o.tau;
  if (o.no_db) cfg.gravity.estimate_gyro_bias = false;
  if (o.gyro_prior > 0) {
    // A gyro-bias prior as from a static calibration: the truth plus noise of that std.
    std::mt19937_64 rng(1000 + static_cast<std::uint64_t>(seed));
    std::normal_distribution<double> n01;
    cfg.velocimeter.gyro_bias_prior = rec.b_g + o.gyro_prior * Vec3(n01(rng), n01(rng), n01(rng));
    cfg.velocimeter.gyro_bias_sigma0 = o.gyro_prior;
  }
  const auto runs = report::runMethods(cfg, rec.imu, rec.frames, rec.extrinsics, o.methods);

  JobResult out;
  const report::TruthFn truth = [&](double t) {
    const auto s = rec.truth(t);
    report::StateTruth gt;
    gt.R_wb = s.R_wb;
    gt.p_w = s.p_w;
    gt.v_w = s.v_w;
    gt.g_w = rec.g_w;
    gt.b_g = rec.b_g;
    gt.b_a = rec.b_a;
    return gt;
  };
  for (const auto& m : runs) {
    const report::EvalRow row = report::makeEvalRow(name, seed, m, truth);
    out.rows.push_back(row);
    char head[96];
    std::snprintf(head, sizeof(head), "%-10s %-16s %2d  ", m.method.c_str(), name.c_str(), seed);
    out.log += head;
    if (!m.result.state.ok()) {
      out.log += "no state: " + row.status + " (" + m.result.state.message + ")\n";
      continue;
    }
    const auto e = sim::evaluate(m.result.state, rec);  // the NEES of the reported covariance
    appendf(out.log, "|v|=%6.2f dv=%7.4f dg=%6.3f deg dbg=%7.5f dba=%6.3f dp=%6.3f m", row.speed,
            row.velocity_err, row.gravity_err_deg, row.gyro_bias_err, row.accel_bias_err,
            row.position_err);
    appendf(out.log, "  nees v=%6.2f tilt=%6.2f bg=%6.2f ba=%6.2f  %7.2f ms\n", e.nees_vel_b,
            e.nees_tilt, e.nees_gyro_bias, e.nees_accel_bias, m.time_ms);
  }
  out.tracks =
      report::velocityTracks(runs, rec.config.t0, [&](double t) -> Vec3 { return truth(t).v_b(); });
  if (o.trace) {
    const auto& fi = out.tracks.front();
    for (std::size_t i = 0; i < fi.t.size(); i += 5) {
      const Vec3 dv = fi.v_est[i] - fi.v_true[i];
      appendf(out.log, "  t=%.3f vb_true=(%6.2f %6.2f %6.2f) dv=(%7.3f %7.3f %7.3f)\n", fi.t[i],
              fi.v_true[i].x(), fi.v_true[i].y(), fi.v_true[i].z(), dv.x(), dv.y(), dv.z());
    }
  }
  return out;
}

/// One figure of panels for the presets whose name starts with `prefix` (first seed).
template <typename Panel>
void writeFigure(const Options& o, const std::vector<std::string>& names,
                 const std::vector<JobResult>& results, const std::string& prefix,
                 const std::string& file, Panel&& panel) {
  std::vector<cv::Mat> panels;
  for (std::size_t p = 0; p < names.size(); ++p) {
    if (names[p].rfind(prefix, 0) != 0) continue;
    const auto& job = results[p * static_cast<std::size_t>(o.seeds)];
    panels.push_back(panel(names[p] + " (seed 1)", job.tracks));
  }
  if (panels.empty()) return;
  const std::string path = (std::filesystem::path(o.plots) / file).string();
  report::savePng(path, report::tile(panels, panels.size() >= 2 ? 2 : 1));
  std::printf("wrote %s\n", path.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Options o = parse(argc, argv);
    const std::size_t n_jobs = o.presets.size() * static_cast<std::size_t>(o.seeds);
    std::vector<JobResult> results(n_jobs);
    report::parallelFor(n_jobs, o.jobs, [&](std::size_t i) {
      const auto& name = o.presets[i / static_cast<std::size_t>(o.seeds)];
      const int seed = 1 + static_cast<int>(i % static_cast<std::size_t>(o.seeds));
      results[i] = runJob(o, name, seed);
      std::fprintf(stderr, "done %s seed %d\n", name.c_str(), seed);
    });

    std::vector<report::EvalRow> rows;
    for (const auto& r : results) {
      if (!o.quiet) std::fputs(r.log.c_str(), stdout);
      rows.insert(rows.end(), r.rows.begin(), r.rows.end());
    }
    report::markFailures(rows, o.thresholds);
    std::printf("\n%s", report::markdownSummary(rows, o.thresholds).c_str());
    if (!o.csv.empty()) report::writeEvalCsv(o.csv, rows);
    if (!o.md.empty()) report::writeEvalMarkdown(o.md, rows, o.thresholds, o.command);
    if (!o.plots.empty()) {
      std::filesystem::create_directories(o.plots);
      writeFigure(o, o.presets, results, "dyna", "velocity_error_dyna.png",
                  [](const std::string& title, const auto& tracks) {
                    return report::velocityErrorPanel(title, tracks, 640, 400);
                  });
      writeFigure(o, o.presets, results, "tunnel", "tunnel_velocity.png",
                  [](const std::string& title, const auto& tracks) {
                    return report::velocityComponentsPanel(title, tracks, 640, 400);
                  });
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "freeinit-eval: %s\n", e.what());
    return 1;
  }
}
