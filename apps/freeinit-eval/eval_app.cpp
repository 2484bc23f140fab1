#include "eval_app.h"

#include <freeinit/io/atomic_file.h>
#include <freeinit/report/figures.h>
#include <freeinit/report/plot.h>
#include <freeinit/report/version.h>
#include <freeinit/sim/evaluation.h>
#include <freeinit/sim/presets.h>
#include <freeinit/sim/random_scenario.h>
#include <freeinit/sim/simulator.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <mutex>
#include <ostream>
#include <random>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace freeinit::apps {
namespace {

using UsageError = EvalApp::UsageError;

const char* const kUsage =
    "Usage: freeinit-eval [options] [preset ...]   (default: every preset)\n"
    "  --seeds N            seeds 1..N per preset (3)\n"
    "  --random N           N randomized scenarios instead of the presets (seeds from "
    "--seed-base;\n"
    "                       the estimator is given the declared calibration and the datasheet\n"
    "                       noise, as a user would)\n"
    "  --seed-base S        first seed of --random (1)\n"
    "  --calibration-sigma DEG, --time-offset-sigma S: the declared calibration's accuracy\n"
    "                       ([joint] calibration_rotation_sigma_deg, time_offset_sigma)\n"
    "  --imu-noise-factor F | LO:HI\n"
    "  --doppler-noise-factor F | LO:HI\n"
    "                       the true noise over the one the estimator is handed (it gets the\n"
    "                       datasheet noise / F; gyro and accelerometer alike), F in [0.01, 100];\n"
    "                       LO:HI: drawn per run, log-uniform, from a stream of its own (a seed's\n"
    "                       recording is the same whatever the factors: runs are paired). The\n"
    "                       bound always uses the true noise. Summaries per factor block\n"
    "  --time-offset S | LO:HI\n"
    "                       an undeclared LiDAR-IMU clock offset of this size [s] in [0, 0.1]\n"
    "                       (LO:HI: uniform per run), either sign, injected into the recording\n"
    "                       (it replaces a randomized scenario's own; these runs are measured\n"
    "                       against their bound, not counted apart as a wrong calibration)\n"
    "  --imu-spikes N:MAG   N accelerometer samples of the window made off by MAG m/s^2 (a\n"
    "                       random axis and sign each, seeded by the run)\n"
    "  --imu-gap S          one IMU gap of S seconds at a random time inside the window\n"
    "  --jobs N             parallel jobs (0: hardware concurrency, the default)\n"
    "  --md FILE            Markdown report (paper Table I/II layout, errors against the\n"
    "                       Cramer-Rao bound, statuses, every run)\n"
    "  --csv FILE           CSV, one row per case and method\n"
    "  --summary-csv FILE   CSV, one row per method: statuses, error/bound quantiles, NEES\n"
    "  --summary-by imu|doppler|imu,doppler\n"
    "                       summaries per factor over the other factor's draws (a row per IMU\n"
    "                       factor, then per Doppler factor) instead of per combination\n"
    "  --bounds-md FILE     the Markdown tables against the bound alone (at most ten\n"
    "                       confident wrong answers listed per method)\n"
    "  --plots DIR          velocity_error_dyna.png and tunnel_velocity.png (first seed)\n"
    "  --fail-velocity V    a run fails above this velocity error [m/s] (0.2)\n"
    "  --fail-gravity D     a run fails above this gravity error [deg] (2)\n"
    "  --duration S         simulated seconds (3.2: DLIO's 3 s calibration; 1.2 with\n"
    "                       --no-baselines)\n"
    "  --points P           points per frame (preset: 60000)\n"
    "  --stride K           point stride, [doppler] point_stride (configuration default)\n"
    "  --window S           window length [s] (configuration default: 0.5)\n"
    "  --no-baselines       Free-Init only\n"
    "  --dlio-duration S    DLIO's static calibration time (3)\n"
    "  --gyro-prior SIGMA   gyro-bias prior: the truth plus noise of this std [rad/s]\n"
    "  --passes N, --seed-samples N, --tau S, --no-gyro-bias-estimate, --zero-gyro-bias:\n"
    "                       estimator variants\n"
    "  --trace              print Free-Init's velocity errors over the window and its\n"
    "                       warnings\n"
    "  -q                   no per-run lines\n"
    "  -h, --help           this text;  --version: the version\n"
    "Exit status: 0 done, 1 a run could not be made, 2 a bad option or value.\n";

/// The parameters of a command line (argv[0] is the program); throws UsageError.
EvalAppParams parseParams(int argc, const char* const* argv) {
  EvalAppParams o;
  for (int i = 1; i < argc; ++i) o.command += std::string(" ") + argv[i];
  auto value = [&](int& i) -> std::string {
    const std::string flag = argv[i];
    if (i + 1 >= argc) throw UsageError(flag + ": needs a value");
    const std::string v = argv[++i];
    if (v.empty() || v.rfind("--", 0) == 0)
      throw UsageError(flag + ": needs a value, not '" + v + "'");
    return v;
  };
  auto text = [](double x) {
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%g", x);
    return std::string(buf);
  };
  // A finite number in [lo, hi] (checked on the double).
  auto number = [&](int& i, double lo, double hi) {
    const std::string flag = argv[i], v = value(i);
    const auto x = report::parseDouble(v);
    if (!x || !std::isfinite(*x)) throw UsageError(flag + ": not a number: '" + v + "'");
    if (!(*x >= lo && *x <= hi))
      throw UsageError(flag + ": must be in [" + text(lo) + ", " + text(hi) + "], not '" + v + "'");
    return *x;
  };
  // "F" or "LO:HI", finite, in [lo, hi], LO <= HI.
  auto range = [&](int& i, double lo, double hi) {
    const std::string flag = argv[i], v = value(i);
    const std::size_t colon = v.find(':');
    const std::string parts[2] = {v.substr(0, colon),
                                  colon == std::string::npos ? v : v.substr(colon + 1)};
    double x[2];
    for (int k = 0; k < 2; ++k) {
      const auto p = report::parseDouble(parts[k]);
      if (!p || !std::isfinite(*p)) throw UsageError(flag + ": not a number or LO:HI: '" + v + "'");
      if (!(*p >= lo && *p <= hi))
        throw UsageError(flag + ": must be in [" + text(lo) + ", " + text(hi) + "], not '" + v +
                         "'");
      x[k] = *p;
    }
    if (x[0] > x[1]) throw UsageError(flag + ": LO must not exceed HI in LO:HI, not '" + v + "'");
    return sim::DrawRange{x[0], x[1]};
  };
  // A positive finite number.
  auto positive = [&](int& i) {
    const std::string flag = argv[i];
    const double x = number(i, 0, 1e9);
    if (!(x > 0)) throw UsageError(flag + ": must be > 0, not '" + argv[i] + "'");
    return x;
  };
  // A whole number in [lo, hi]: a fraction or an out-of-range value is an error, not rounded
  // (checked on the double, before any conversion).
  auto integer = [&](int& i, int lo, int hi) {
    const std::string flag = argv[i];
    const auto x = report::parseDouble(value(i));
    if (!x || !(*x >= lo && *x <= hi) || *x != std::floor(*x))
      throw UsageError(flag + ": must be a whole number in [" + std::to_string(lo) + ", " +
                       std::to_string(hi) + "], not '" + argv[i] + "'");
    return static_cast<int>(*x);
  };
  const std::map<std::string, std::function<void(int&)>> with_value = {
      {"--seeds", [&](int& i) { o.seeds = integer(i, 1, 100000); }},
      {"--random", [&](int& i) { o.random = integer(i, 1, 1000000); }},
      {"--seed-base", [&](int& i) { o.seed_base = integer(i, 0, 2000000000); }},
      {"--calibration-sigma", [&](int& i) { o.calibration_sigma = number(i, 0, 10); }},
      {"--time-offset-sigma", [&](int& i) { o.time_offset_sigma = number(i, 0, 0.1); }},
      {"--imu-noise-factor", [&](int& i) { o.imu_noise_factor = range(i, 0.01, 100); }},
      {"--doppler-noise-factor", [&](int& i) { o.doppler_noise_factor = range(i, 0.01, 100); }},
      {"--time-offset", [&](int& i) { o.time_offset = range(i, 0, 0.1); }},
      {"--imu-spikes",
       [&](int& i) {
         const std::string flag = argv[i], v = value(i);
         const std::size_t colon = v.find(':');
         const auto n = report::parseDouble(v.substr(0, colon));
         const auto mag =
             colon == std::string::npos ? std::nullopt : report::parseDouble(v.substr(colon + 1));
         if (!n || !mag || !(*n >= 0 && *n <= 1000) || *n != std::floor(*n) ||
             !(std::abs(*mag) <= 1e6))
           throw UsageError(flag +
                            ": must be N:MAG, N a whole number in [0, 1000], |MAG| <= "
                            "1e6 m/s^2, not '" +
                            v + "'");
         o.imu_spikes = static_cast<int>(*n);
         o.imu_spike_magnitude = *mag;
       }},
      {"--imu-gap", [&](int& i) { o.imu_gap = number(i, 0, 10); }},
      {"--jobs", [&](int& i) { o.jobs = static_cast<unsigned>(integer(i, 0, 1024)); }},
      {"--md", [&](int& i) { o.md = value(i); }},
      {"--csv", [&](int& i) { o.csv = value(i); }},
      {"--summary-csv", [&](int& i) { o.summary_csv = value(i); }},
      {"--summary-by",
       [&](int& i) {
         const std::string flag = argv[i], v = value(i);
         o.summary_by.clear();
         std::size_t from = 0;
         while (from <= v.size()) {
           const std::size_t comma = std::min(v.find(',', from), v.size());
           const std::string part = v.substr(from, comma - from);
           if ((part != "imu" && part != "doppler") ||
               std::find(o.summary_by.begin(), o.summary_by.end(), part) != o.summary_by.end())
             throw UsageError(flag + ": must be imu, doppler or imu,doppler, not '" + v + "'");
           o.summary_by.push_back(part);
           from = comma + 1;
         }
       }},
      {"--bounds-md", [&](int& i) { o.bounds_md = value(i); }},
      {"--plots", [&](int& i) { o.plots = value(i); }},
      {"--fail-velocity", [&](int& i) { o.thresholds.velocity = positive(i); }},
      {"--fail-gravity", [&](int& i) { o.thresholds.gravity_deg = positive(i); }},
      {"--duration", [&](int& i) { o.duration = positive(i); }},
      {"--points", [&](int& i) { o.points = integer(i, 1, 100000000); }},
      {"--stride", [&](int& i) { o.stride = integer(i, 1, 1000000); }},
      {"--window", [&](int& i) { o.window = positive(i); }},
      {"--dlio-duration", [&](int& i) { o.methods.dlio_duration = positive(i); }},
      {"--gyro-prior", [&](int& i) { o.gyro_prior = number(i, 0, 10); }},
      {"--passes", [&](int& i) { o.passes = integer(i, 0, 1000); }},
      {"--seed-samples", [&](int& i) { o.seed_samples = integer(i, 0, 1000000); }},
      {"--tau", [&](int& i) { o.tau = number(i, 0, 1e6); }},
  };
  const std::map<std::string, bool*> switches = {{"--no-gyro-bias-estimate", &o.no_db},
                                                 {"--zero-gyro-bias", &o.zero_bg},
                                                 {"--trace", &o.trace},
                                                 {"-q", &o.quiet}};
  const auto names = sim::presetNames();
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (const auto f = with_value.find(a); f != with_value.end()) {
      f->second(i);
    } else if (const auto sw = switches.find(a); sw != switches.end()) {
      *sw->second = true;
    } else if (a == "--no-baselines") {
      o.methods.baselines = false;
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError(a + ": unknown option");
    } else if (std::find(names.begin(), names.end(), a) == names.end()) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
      throw UsageError(a + ": not a preset (" + list + ")");
    } else {
      o.presets.push_back(a);
    }
  }
  return o;
}

/// The parameters run() works with: the duration and the presets filled in.
EvalAppParams resolved(EvalAppParams o) {
  if (o.duration < 0) o.duration = o.methods.baselines ? o.methods.dlio_duration + 0.2 : 1.2;
  if (o.presets.empty()) o.presets = sim::presetNames();
  return o;
}

/// The summary block of a run: each misdeclaration the command line asks for, a fixed value as
/// it is, a drawn factor binned to the nearest power of two ("imu≈×2"), a drawn offset by its
/// range.
std::string blockOf(const EvalAppParams& o, const sim::Misdeclaration& m,
                    const std::string& only = "") {
  auto format = [](const char* fmt, double x) {
    char buf[48];
    std::snprintf(buf, sizeof(buf), fmt, x);
    return std::string(buf);
  };
  auto factor = [&](const char* name, const std::optional<sim::DrawRange>& r, double f) {
    if (!r) return std::string();
    if (r->lo == r->hi) return std::string(name) + "×" + format("%g", f);
    return std::string(name) + "≈×" + format("%g", std::exp2(std::round(std::log2(f))));
  };
  std::string block;
  for (std::string part :
       {only == "doppler" ? "" : factor("imu", o.imu_noise_factor, m.imu_noise_factor),
        only == "imu" ? "" : factor("doppler", o.doppler_noise_factor, m.doppler_noise_factor)})
    if (!part.empty()) block += (block.empty() ? "" : " ") + part;
  if (o.time_offset) {
    const sim::DrawRange& t = *o.time_offset;
    block += std::string(block.empty() ? "" : " ") + "offset±" + format("%g", 1e3 * t.lo) +
             (t.lo == t.hi ? "" : "-" + format("%g", 1e3 * t.hi)) + "ms";
  }
  return block;
}

/// The command line's changes to a case (duration, points, the zero-gyro-bias variant, what the
/// estimator is handed and the injected clock offset).
void applyOverrides(const EvalAppParams& o, EvalCase& c) {
  sim::ScenarioConfig& sc = c.scenario;
  sc.duration = o.duration;
  if (o.points > 0) sc.points_per_frame = o.points;
  if (o.zero_bg) {
    sc.random_biases = false;
    sc.b_g.setZero();
    sc.b_a = Vec3(0.1, -0.08, 0.05);
  }
  sim::MisdeclarationRanges ranges;
  if (o.imu_noise_factor) ranges.imu_noise_factor = *o.imu_noise_factor;
  if (o.doppler_noise_factor) ranges.doppler_noise_factor = *o.doppler_noise_factor;
  if (o.time_offset) ranges.time_offset = *o.time_offset;
  c.misdeclared = sim::drawMisdeclaration(static_cast<std::uint64_t>(c.seed), ranges);
  if (o.time_offset) {
    sc.lidar_time_offset = c.misdeclared.time_offset;
    c.wrong_calibration =
        sc.declared_rotation_error_deg.norm() > 0 || sc.declared_position_error.norm() > 0;
  }
  c.block = blockOf(o, c.misdeclared);
  for (const std::string& by : o.summary_by)
    c.summary_blocks.push_back(blockOf(o, c.misdeclared, by));
}

/// Every preset of the command line x seeds 1..N. (Randomized scenarios are one more function of
/// this kind: N seeds from a base, each sim::randomScenario(seed) through applyOverrides.)
std::vector<EvalCase> presetCases(const EvalAppParams& o) {
  std::vector<EvalCase> cases;
  for (const auto& name : o.presets)
    for (int seed = 1; seed <= o.seeds; ++seed) {
      EvalCase c;
      c.source = name;
      c.seed = seed;
      c.scenario = sim::preset(name, static_cast<std::uint64_t>(seed));
      applyOverrides(o, c);
      cases.push_back(std::move(c));
    }
  return cases;
}

/// N randomized scenarios from the seed base, named in the tables by platform and start
/// ("handheld/static", "vehicular/moving", ...).
std::vector<EvalCase> randomCases(const EvalAppParams& o) {
  std::vector<EvalCase> cases;
  for (long long seed = o.seed_base; seed < o.seed_base + o.random; ++seed) {
    const sim::RandomScenario r = sim::drawRandomScenario(static_cast<std::uint64_t>(seed));
    EvalCase c;
    c.source = std::string(sim::platformName(r.info.platform)) + "/" + r.info.start;
    c.seed = static_cast<int>(seed);
    c.scenario = r.config;
    c.wrong_calibration = r.info.calibration_wrong;
    applyOverrides(o, c);
    cases.push_back(std::move(c));
  }
  return cases;
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

/// Whether the estimator is handed the scenario's datasheet noise (over the factors) rather than
/// the configuration's default.
bool declaresDatasheetNoise(const EvalAppParams& o) {
  return o.random > 0 || o.imu_noise_factor || o.doppler_noise_factor;
}

FreeInitConfig configFor(const EvalAppParams& o, const EvalCase& c, const sim::Recording& rec) {
  FreeInitConfig cfg;
  if (o.calibration_sigma >= 0) cfg.joint.calibration_rotation_sigma_deg = o.calibration_sigma;
  if (o.time_offset_sigma >= 0) cfg.joint.time_offset_sigma = o.time_offset_sigma;
  if (declaresDatasheetNoise(o)) {
    // What a user of this rig would configure: the datasheet noise (the unit's own per-axis
    // values scatter about it), wrong by the run's factors, and the calibration as declared
    // (runMethods takes the extrinsics).
    cfg.doppler.doppler_sigma = rec.config.doppler_sigma / c.misdeclared.doppler_noise_factor;
    cfg.imu.gyro_sigma = rec.config.gyro_sigma / c.misdeclared.imu_noise_factor;
    cfg.imu.accel_sigma = rec.config.accel_sigma / c.misdeclared.imu_noise_factor;
  }
  if (o.stride > 0) cfg.doppler.point_stride = o.stride;
  if (o.window > 0) cfg.window.duration = o.window;
  if (o.passes >= 0) cfg.paper_passes.refinement_passes = o.passes;
  if (o.seed_samples >= 0) cfg.paper_passes.seed_duration = o.seed_samples / rec.config.imu_rate;
  if (o.tau >= 0) cfg.paper_gravity.velocity_error_correlation_time = o.tau;
  if (o.no_db) cfg.paper_gravity.estimate_gyro_bias = false;
  if (o.gyro_prior > 0) {
    // A gyro-bias prior as from a static calibration: the truth plus noise of that std.
    std::mt19937_64 rng(1000 + static_cast<std::uint64_t>(c.seed));
    std::normal_distribution<double> n01;
    cfg.imu.gyro_bias_prior = rec.b_g + o.gyro_prior * Vec3(n01(rng), n01(rng), n01(rng));
    cfg.imu.gyro_bias_sigma0 = o.gyro_prior;
  }
  return cfg;
}

/// --imu-spikes and --imu-gap: the faults, at times drawn from the run's seed inside the window
/// (which starts at the first LiDAR point).
void injectImuFaults(const EvalAppParams& o, const EvalCase& c, const FreeInitConfig& cfg,
                     sim::Recording& rec) {
  if ((o.imu_spikes == 0 && !(o.imu_gap > 0)) || rec.frames.empty() || rec.imu.empty()) return;
  const LidarFrame& f = rec.frames.front();
  const double t0 = f.stamp + (f.points.empty() ? 0.0 : f.points.front().time_offset);
  const double T = cfg.window.duration;
  std::mt19937_64 rng(0x44F00000ULL + static_cast<std::uint64_t>(c.seed));
  std::uniform_real_distribution<double> u(0, 1);
  auto indexAt = [&](double t) {
    return static_cast<std::size_t>(
        std::lower_bound(rec.imu.begin(), rec.imu.end(), t,
                         [](const ImuSample& s, double x) { return s.t < x; }) -
        rec.imu.begin());
  };
  for (int n = 0; n < o.imu_spikes; ++n) {
    const std::size_t k = indexAt(t0 + 0.02 * T + 0.96 * T * u(rng));
    const int axis = std::min(2, static_cast<int>(3 * u(rng)));
    const double sign = u(rng) < 0.5 ? -1.0 : 1.0;
    if (k < rec.imu.size()) rec.imu[k].accel(axis) += sign * o.imu_spike_magnitude;
  }
  if (o.imu_gap > 0) {
    const double start = t0 + 0.05 * T + (0.9 * T - std::min(o.imu_gap, 0.9 * T)) * u(rng);
    const auto first = rec.imu.begin() + static_cast<std::ptrdiff_t>(indexAt(start));
    const auto last = rec.imu.begin() + static_cast<std::ptrdiff_t>(indexAt(start + o.imu_gap));
    rec.imu.erase(first, last);
  }
}

JobResult runCase(const EvalAppParams& o, const EvalCase& c) {
  sim::Recording rec = sim::simulate(c.scenario);
  injectImuFaults(o, c, configFor(o, c, rec), rec);
  const FreeInitConfig cfg = configFor(o, c, rec);
  const sim::NoiseFigures truth_noise = sim::trueNoise(rec);
  const auto runs =
      report::runMethods(cfg, rec.imu, rec.frames, rec.declared_extrinsics, o.methods);

  // The bound of each method's window (methods with the same window share it), with the
  // estimator's priors.
  const eval::BoundModel model = sim::boundModel(rec, cfg);
  std::map<std::pair<double, double>, eval::Bound> bounds;
  auto boundOf = [&](const InitResult& r) -> const eval::Bound* {
    if (!r.state.ok() || r.trajectory.empty()) return nullptr;
    const std::pair<double, double> window(r.trajectory.front().t, r.state.timestamp);
    auto it = bounds.find(window);
    if (it == bounds.end())
      it = bounds.emplace(window, sim::cramerRaoBound(rec, model, window.first, window.second))
               .first;
    return &it->second;
  };

  JobResult out;
  const report::TruthFn truth = [&](double t) { return sim::stateTruth(rec, t); };
  for (const auto& m : runs) {
    report::EvalRow row = report::makeEvalRow(c.source, c.seed, m, truth, boundOf(m.result));
    row.wrong_calibration = c.wrong_calibration;
    row.block = c.block;
    const bool datasheet = declaresDatasheetNoise(o);
    row.imu_noise_factor =
        datasheet ? c.misdeclared.imu_noise_factor : rec.config.gyro_sigma / cfg.imu.gyro_sigma;
    row.doppler_noise_factor = datasheet ? c.misdeclared.doppler_noise_factor
                                         : rec.config.doppler_sigma / cfg.doppler.doppler_sigma;
    row.noise_gyro.declared = cfg.imu.gyro_sigma;
    row.noise_accel.declared = cfg.imu.accel_sigma;
    row.noise_doppler.declared = cfg.doppler.doppler_sigma;
    row.noise_gyro.truth = truth_noise.gyro;
    row.noise_accel.truth = truth_noise.accel;
    row.noise_doppler.truth = truth_noise.doppler;
    row.time_offset_true = rec.lidar_time_offset;
    out.rows.push_back(row);
    char head[96];
    std::snprintf(head, sizeof(head), "%-10s %-16s %2d  ", m.method.c_str(), c.source.c_str(),
                  c.seed);
    out.log += head;
    if (!m.result.state.ok()) {
      out.log += "no state: " + row.status + " (" + m.result.state.message + ")\n";
      continue;
    }
    appendf(out.log, "|v|=%6.2f dv=%7.4f dg=%6.3f deg dbg=%7.5f dba=%6.3f dp=%6.3f m", row.speed,
            row.velocity_err, row.gravity_err_deg, row.gyro_bias_err, row.accel_bias_err,
            row.position_err);
    appendf(out.log, "  err/crb v=%5.2f g=%5.2f bg=%5.2f ba=%5.2f", row.ratioVelocity(),
            row.ratioGravity(), row.ratioGyroBias(), row.ratioAccelBias());
    appendf(out.log, "  nees v=%6.2f tilt=%6.2f bg=%6.2f ba=%6.2f  %7.2f ms", row.nees_velocity,
            row.nees_tilt, row.nees_gyro_bias, row.nees_accel_bias, m.time_ms);
    if (row.rest_samples > 0)
      appendf(out.log, "  bg/zero-rate=%.2f (rest %d of %d)", row.ratioGyroBiasZeroRate(),
              row.rest_samples, row.window_samples);
    if (!c.block.empty())
      appendf(out.log, "  factors imu=%.3g doppler=%.3g offset=%.2f ms", row.imu_noise_factor,
              row.doppler_noise_factor, 1e3 * row.time_offset_true);
    const std::string wrong = row.confidentlyWrong();
    if (m.method == "free-init")
      appendf(
          out.log, "  rms/sigma=%.3f node-chi2/dof=%.2f used=%.2f",
          m.result.diag.doppler_residual_rms / cfg.doppler.doppler_sigma,
          m.result.diag.node_residual_ratio,
          static_cast<double>(m.result.diag.points_used) /
              std::max<std::size_t>(1, m.result.diag.points_used + m.result.diag.points_rejected));
    if (m.method == "free-init" && (o.imu_spikes > 0 || o.imu_gap > 0))
      appendf(out.log, "  imu_faults=%zu imu_gap=%.3f s", m.result.diag.imu_faults,
              m.result.diag.imu_gap_s);
    if (!m.result.state.warnings.empty())
      appendf(out.log, "  %zu warning(s)", m.result.state.warnings.size());
    if (c.wrong_calibration) out.log += "  [wrong calibration]";
    out.log += wrong.empty() ? "\n" : "  CONFIDENT WRONG: " + wrong + "\n";
    if (o.trace)
      for (const std::string& w : m.result.state.warnings) out.log += "    warning: " + w + "\n";
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

/// One figure of panels for the inputs whose name starts with `prefix` (the first case of each).
template <typename Panel>
void writeFigure(std::ostream& out, const EvalAppParams& o, const std::vector<EvalCase>& cases,
                 const std::vector<JobResult>& results, const std::string& prefix,
                 const std::string& file, Panel&& panel) {
  std::vector<cv::Mat> panels;
  std::vector<std::string> done;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const EvalCase& c = cases[i];
    if (c.source.rfind(prefix, 0) != 0) continue;
    if (std::find(done.begin(), done.end(), c.source) != done.end()) continue;
    done.push_back(c.source);
    panels.push_back(panel(c.source + " (seed " + std::to_string(c.seed) + ")", results[i].tracks));
  }
  if (panels.empty()) return;
  const std::string path = (std::filesystem::path(o.plots) / file).string();
  report::savePng(path, report::tile(panels, panels.size() >= 2 ? 2 : 1));
  out << "wrote " << path << "\n";
}

/// Creates the folders the outputs go to before any run, so that a path that cannot be written
/// fails at once, naming its option, not after the evaluation.
void prepareOutputFolders(const EvalAppParams& o) {
  namespace fs = std::filesystem;
  const std::pair<const char*, fs::path> folders[] = {
      {"--md", fs::path(o.md).parent_path()},
      {"--csv", fs::path(o.csv).parent_path()},
      {"--summary-csv", fs::path(o.summary_csv).parent_path()},
      {"--bounds-md", fs::path(o.bounds_md).parent_path()},
      {"--plots", fs::path(o.plots)}};
  for (const auto& [flag, folder] : folders) {
    if (folder.empty()) continue;
    std::error_code ec;
    fs::create_directories(folder, ec);
    if (ec || !fs::is_directory(folder))
      throw std::runtime_error(std::string(flag) + ": cannot create the folder " + folder.string() +
                               (ec ? ": " + ec.message() : ""));
  }
}

}  // namespace

const char* EvalApp::usage() { return kUsage; }

EvalApp::Action EvalApp::parse(int argc, const char* const* argv) {
  // --help and --version print and exit whatever else is on the line.
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") return Action::Help;
    if (a == "--version") return Action::Version;
  }
  params = parseParams(argc, argv);
  return Action::Run;
}

std::vector<EvalCase> EvalApp::cases() const {
  const EvalAppParams o = resolved(params);
  return o.random > 0 ? randomCases(o) : presetCases(o);
}

void EvalApp::run(std::ostream& out, std::ostream& progress) {
  const EvalAppParams o = resolved(params);
  prepareOutputFolders(o);
  const std::vector<EvalCase> cases = this->cases();
  std::vector<JobResult> results(cases.size());
  std::mutex progress_mutex;
  report::parallelFor(cases.size(), o.jobs, [&](std::size_t i) {
    results[i] = runCase(o, cases[i]);
    const std::string done =
        "done " + cases[i].source + " seed " + std::to_string(cases[i].seed) + "\n";
    const std::lock_guard<std::mutex> lock(progress_mutex);
    progress << done << std::flush;
  });

  rows.clear();
  for (const auto& r : results) {
    if (!o.quiet) out << r.log;
    rows.insert(rows.end(), r.rows.begin(), r.rows.end());
  }
  report::markFailures(rows, o.thresholds);
  // The summaries' rows: each run under its block, or once per marginal block (--summary-by).
  std::vector<report::EvalRow> summarized;
  for (std::size_t q = 0; q < o.summary_by.size(); ++q)
    for (std::size_t i = 0, k = 0; i < results.size(); ++i)
      for (std::size_t j = 0; j < results[i].rows.size(); ++j, ++k) {
        summarized.push_back(rows[k]);
        summarized.back().block = cases[i].summary_blocks[q];
      }
  const std::vector<report::EvalRow>& summary_rows = o.summary_by.empty() ? rows : summarized;
  out << "\n"
      << report::markdownSummary(rows, o.thresholds) << "\n"
      << report::boundsMarkdown(summary_rows);
  if (!o.csv.empty()) report::writeEvalCsv(o.csv, rows);
  if (!o.summary_csv.empty()) report::writeSummaryCsv(o.summary_csv, summary_rows);
  if (!o.md.empty()) report::writeEvalMarkdown(o.md, rows, o.thresholds, o.command);
  if (!o.bounds_md.empty()) {
    // For a README: ten confident wrong answers per method at most (the report lists all).
    const std::string md = report::boundsMarkdown(summary_rows, {}, 10);
    writeFileAtomically(o.bounds_md, [&](std::ostream& f) { f << md; });
  }
  if (!o.plots.empty()) {
    std::filesystem::create_directories(o.plots);
    writeFigure(out, o, cases, results, "dyna", "velocity_error_dyna.png",
                [](const std::string& title, const auto& tracks) {
                  return report::velocityErrorPanel(title, tracks, 640, 400);
                });
    writeFigure(out, o, cases, results, "tunnel", "tunnel_velocity.png",
                [](const std::string& title, const auto& tracks) {
                  return report::velocityComponentsPanel(title, tracks, 640, 400);
                });
  }
}

int EvalApp::main(int argc, const char* const* argv) {
  EvalApp app;
  try {
    switch (app.parse(argc, argv)) {
      case Action::Help:
        std::cout << usage();
        return 0;
      case Action::Version:
        std::cout << "freeinit-eval " << report::version() << "\n";
        return 0;
      case Action::Run:
        break;
    }
  } catch (const UsageError& e) {  // as every app's command line (mrpt_plugins/command_line.h)
    std::cerr << "freeinit-eval: error: " << e.what() << "; see 'freeinit-eval --help'\n";
    return 2;
  }
  try {
    app.run(std::cout, std::cerr);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "freeinit-eval: error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace freeinit::apps
