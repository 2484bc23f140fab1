// freeinit-eval: Free-Init and the baseline initializers (FAST-LIO2 and DLIO static means,
// per-frame Doppler least squares) on simulated scenarios, against the ground truth and against
// the Cramer-Rao bound of each run (freeinit/eval).
// What it runs is a list of cases (a scenario config and its name in the tables): the presets x
// seeds, or randomized scenarios. Jobs (one per case) are independent and deterministic and run
// in parallel; the tables are the same whatever `jobs` (only the wall times differ).
#pragma once

#include <freeinit/report/eval_table.h>
#include <freeinit/report/methods.h>
#include <freeinit/sim/random_scenario.h>
#include <freeinit/sim/scenario.h>

#include <iosfwd>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace freeinit::apps {

/// What freeinit-eval runs and writes; the defaults are those of its command line.
struct EvalAppParams {
  int seeds = 3;            ///< seeds 1..N per preset
  int random = 0;           ///< > 0: this many randomized scenarios instead of the presets
  long long seed_base = 1;  ///< first seed of the randomized scenarios
  /// The declared calibration's accuracy ([joint] calibration_rotation_sigma_deg [deg],
  /// time_offset_sigma [s]); < 0: the configuration default.
  double calibration_sigma = -1, time_offset_sigma = -1;
  unsigned jobs = 0;  ///< parallel jobs (0: hardware concurrency)
  /// Output files (empty: none): Markdown report, CSV per run, CSV per method, the Markdown
  /// tables against the bound, and the folder of the figures.
  std::string md, csv, summary_csv, bounds_md, plots;
  report::FailureThresholds thresholds;
  double duration = -1;   ///< [s] simulated; < 0: dlio_duration + 0.2 with baselines, else 1.2
  int points = 0;         ///< points per frame; 0: the preset's
  int stride = 0;         ///< [doppler] point_stride; 0: the configuration default
  int passes = -1;        ///< window refinement passes; < 0: the configuration default
  int seed_samples = -1;  ///< IMU samples of the seed; < 0: the configuration default
  double window = 0;      ///< [s] window length; 0: the configuration default
  double tau = -1;        ///< [s] velocity error correlation time; < 0: the configuration default
  double gyro_prior = 0;  ///< [rad/s] > 0: a gyro-bias prior, the truth plus noise of this std
  bool zero_bg = false;   ///< scenarios with zero gyro bias (and a fixed accelerometer bias)
  bool no_db = false;     ///< the gravity stage does not estimate the gyro bias
  bool trace = false;     ///< log Free-Init's velocity errors over the window
  bool quiet = false;     ///< no per-run lines
  report::MethodOptions methods;
  std::vector<std::string> presets;       ///< empty: every preset
  std::string command = "freeinit-eval";  ///< the command line, for the Markdown report
  /// What the estimator is handed instead of the truth, drawn per run (sim::drawMisdeclaration,
  /// seeded by the run's seed): [-] the true noise over the declared one, IMU and Doppler (the
  /// estimator gets the datasheet noise / factor), and [s] |an undeclared LiDAR-IMU clock offset|
  /// injected into the recording. Unset: the datasheet noise (--random) or the configuration's
  /// (presets), and the scenario's own offset.
  std::optional<sim::DrawRange> imu_noise_factor, doppler_noise_factor, time_offset;
  /// The factors whose marginal blocks the summaries give instead of one block per combination
  /// ("imu", "doppler", or both: each run then counts once under each), e.g. a row per IMU
  /// factor over every Doppler factor. Empty: one block per combination.
  std::vector<std::string> summary_by;
  /// Gross IMU faults injected into each recording (issue 44): imu_spikes accelerometer samples
  /// of the window, each on a random axis with a random sign, made off by imu_spike_magnitude
  /// [m/s^2]; and [s] one IMU gap of imu_gap at a random time inside the window (0: none).
  /// Seeded by the run's seed.
  int imu_spikes = 0;
  double imu_spike_magnitude = 0;
  double imu_gap = 0;
};

/// One run of the evaluation: a scenario of the simulator, its name in the tables and what the
/// estimator is handed instead of the truth.
struct EvalCase {
  std::string source;  ///< the tables' input column
  int seed = 0;        ///< the tables' seed column
  sim::ScenarioConfig scenario;
  /// The declared extrinsics or clock are wrong on purpose (the randomized scenario's draw; an
  /// offset injected with --time-offset is not: those runs are measured against their bound).
  bool wrong_calibration = false;
  sim::Misdeclaration misdeclared;  ///< the noise factors and the offset (in `scenario` already)
  std::string block;                ///< the summary block (report::EvalRow::block)
  std::vector<std::string> summary_blocks;  ///< its block per EvalAppParams::summary_by entry
};

class EvalApp {
 public:
  /// A bad command line (exit status 2): one line that starts with the flag or argument.
  struct UsageError : std::invalid_argument {
    using std::invalid_argument::invalid_argument;
  };
  /// What a command line asks for.
  enum class Action { Run, Help, Version };

  EvalAppParams params;

  /// The --help text.
  static const char* usage();

  /// Sets `params` from a command line (argv[0] is the program). -h, --help and --version win
  /// whatever else is on the line (the first of them); otherwise every argument is checked and
  /// the first bad one throws UsageError, leaving `params` unchanged.
  Action parse(int argc, const char* const* argv);

  /// Runs the evaluation of `params`: the per-run lines (unless quiet), the summary and bound
  /// tables and "wrote" lines on `out`, one "done" line per case on `progress`, the files asked
  /// for. The folders of the outputs are created first: one that cannot be throws, naming its
  /// option, before any run. Throws on any error.
  void run(std::ostream& out, std::ostream& progress);

  /// The runs `params` asks for, in table order: run() simulates each scenario as given here.
  std::vector<EvalCase> cases() const;

  /// After run(): one row per case and method, failures marked, in the order of the tables.
  std::vector<report::EvalRow> rows;

  /// The command line (`main` of freeinit-eval): parses it, prints the help or the version, or
  /// runs on std::cout / std::cerr; returns the exit code (0 done, 1 a run could not be made, 2 a
  /// bad option or value), each error one line on std::cerr.
  static int main(int argc, const char* const* argv);
};

}  // namespace freeinit::apps
