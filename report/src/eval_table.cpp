#include <freeinit/eval/state_errors.h>
#include <freeinit/initial_state.h>
#include <freeinit/io/atomic_file.h>
#include <freeinit/report/eval_table.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace freeinit::report {
namespace {

// Column order of the CSV; readEvalCsv requires exactly this header. The ratio columns and
// confident_wrong are derived from the others.
constexpr char kHeader[] =
    "source,seed,method,status,speed_mps,velocity_err_mps,gravity_err_deg,gravity_bound_deg,"
    "gyro_bias_err_radps,accel_bias_err_mps2,position_err_m,time_ms,crb_velocity_mps,"
    "crb_gravity_deg,crb_gyro_bias_radps,crb_accel_bias_mps2,nees_velocity,nees_tilt,"
    "nees_gyro_bias,nees_accel_bias,sigma_velocity_mps,sigma_gravity_deg,sigma_gyro_bias_radps,"
    "sigma_accel_bias_mps2,ratio_velocity,ratio_gravity,ratio_gyro_bias,ratio_accel_bias,"
    "confident_wrong,failed,failure,warnings,wrong_calibration,rest_s,block,imu_noise_factor,"
    "doppler_noise_factor,noise_gyro_declared_radps,noise_gyro_true_radps,"
    "noise_gyro_reported_radps,noise_gyro_reported_rel_sigma,noise_accel_declared_mps2,"
    "noise_accel_true_mps2,noise_accel_reported_mps2,noise_accel_reported_rel_sigma,"
    "noise_doppler_declared_mps,noise_doppler_true_mps,noise_doppler_reported_mps,"
    "noise_doppler_reported_rel_sigma,time_offset_true_s,time_offset_reported_s,"
    "time_offset_reported_sigma_s,crb_gyro_bias_zero_rate_radps,window_samples,rest_samples,"
    "ratio_gyro_bias_zero_rate";
constexpr std::size_t columnsOf(const char* header) {
  std::size_t n = 1;
  for (const char* c = header; *c != '\0'; ++c) n += *c == ',' ? 1 : 0;
  return n;
}
constexpr std::size_t kColumns = 56;
static_assert(columnsOf(kHeader) == kColumns, "kHeader and kColumns disagree");
constexpr std::size_t kFirstRatioColumn = 24;
constexpr std::size_t kConfidentWrongColumn = 28;
constexpr std::size_t kFailedColumn = 29, kFailureColumn = 30, kWarningsColumn = 31,
                      kWrongCalibrationColumn = 32, kRestColumn = 33, kBlockColumn = 34,
                      kFirstMisdeclarationColumn = 35, kWindowSamplesColumn = 53,
                      kRestSamplesColumn = 54, kZeroRateRatioColumn = 55;

/// The stored numeric fields of a row, in CSV order after "status".
std::vector<double*> numbers(EvalRow& r) {
  return {&r.speed,          &r.velocity_err,      &r.gravity_err_deg, &r.gravity_bound_deg,
          &r.gyro_bias_err,  &r.accel_bias_err,    &r.position_err,    &r.time_ms,
          &r.crb_velocity,   &r.crb_gravity_deg,   &r.crb_gyro_bias,   &r.crb_accel_bias,
          &r.nees_velocity,  &r.nees_tilt,         &r.nees_gyro_bias,  &r.nees_accel_bias,
          &r.sigma_velocity, &r.sigma_gravity_deg, &r.sigma_gyro_bias, &r.sigma_accel_bias};
}

/// The stored numeric fields of a row after "block", in CSV order (up to window_samples).
std::vector<double*> misdeclarationNumbers(EvalRow& r) {
  std::vector<double*> out = {&r.imu_noise_factor, &r.doppler_noise_factor};
  for (SensorNoise* n : {&r.noise_gyro, &r.noise_accel, &r.noise_doppler})
    for (double* x : {&n->declared, &n->truth, &n->reported, &n->reported_rel_sigma})
      out.push_back(x);
  for (double* x : {&r.time_offset_true, &r.time_offset_reported, &r.time_offset_reported_sigma,
                    &r.crb_gyro_bias_zero_rate})
    out.push_back(x);
  return out;
}

/// A count that may be unknown (-1: empty).
std::string count(int n) { return n < 0 ? std::string() : std::to_string(n); }

/// The derived ratios of a row, in CSV order.
std::vector<double> ratios(const EvalRow& r) {
  return {r.ratioVelocity(), r.ratioGravity(), r.ratioGyroBias(), r.ratioAccelBias()};
}

std::string quoted(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += (c == '"') ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

/// %.10g (round trip to 1e-10 relative), empty for NaN, "inf" for an infinite value.
std::string number(double x) {
  if (std::isnan(x)) return "";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.10g", x);
  return buf;
}

/// Splits one CSV line (RFC 4180 quoting, no embedded line breaks).
std::vector<std::string> splitCsv(const std::string& line, const std::string& where) {
  std::vector<std::string> out(1);
  bool in_quotes = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (in_quotes) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        out.back() += '"';
        ++i;
      } else if (c == '"') {
        in_quotes = false;
      } else {
        out.back() += c;
      }
    } else if (c == '"') {
      in_quotes = true;
    } else if (c == ',') {
      out.emplace_back();
    } else {
      out.back() += c;
    }
  }
  if (in_quotes) throw std::runtime_error(where + ": unterminated quoted field");
  return out;
}

double parseNumber(const std::string& s, const std::string& where) {
  if (s.empty()) return kNoValue;
  const auto x = parseDouble(s);
  if (!x) throw std::runtime_error(where + ": not a number: '" + s + "'");
  return *x;
}

/// Compact number for tables: 3 significant digits, no exponent for the ranges seen here.
std::string shortNumber(double x) {
  if (std::isnan(x)) return "–";
  if (std::isinf(x)) return x > 0 ? "∞" : "-∞";
  char buf[32];
  const double a = std::abs(x);
  if (a == 0) return "0";
  if (a >= 100)
    std::snprintf(buf, sizeof(buf), "%.0f", x);
  else if (a >= 10)
    std::snprintf(buf, sizeof(buf), "%.1f", x);
  else if (a >= 1)
    std::snprintf(buf, sizeof(buf), "%.2f", x);
  else if (a >= 0.001)
    std::snprintf(buf, sizeof(buf), "%#.2g", x);
  else
    std::snprintf(buf, sizeof(buf), "%.1e", x);
  return buf;
}

/// Items in order of first appearance.
template <typename Get>
std::vector<std::string> ordered(const std::vector<EvalRow>& rows, Get get) {
  std::vector<std::string> out;
  for (const auto& r : rows)
    if (std::find(out.begin(), out.end(), get(r)) == out.end()) out.push_back(get(r));
  return out;
}

struct Metric {
  const char* label;
  double EvalRow::*field;
  bool mean;         ///< mean over seeds (time); otherwise the worst
  double threshold;  ///< values above it are marked; NaN: none
};

}  // namespace

void markFailures(std::vector<EvalRow>& rows, const FailureThresholds& th) {
  for (auto& r : rows) {
    r.failed = false;
    r.failure.clear();
    char buf[96];
    if (r.status != "ok") {
      r.failed = true;
      r.failure = "status " + r.status;
    } else if (r.velocity_err > th.velocity) {
      std::snprintf(buf, sizeof(buf), "velocity error %.3g > %.3g m/s", r.velocity_err,
                    th.velocity);
      r.failed = true;
      r.failure = buf;
    } else if (r.gravity_err_deg > th.gravity_deg) {
      std::snprintf(buf, sizeof(buf), "gravity error %.3g > %.3g deg", r.gravity_err_deg,
                    th.gravity_deg);
      r.failed = true;
      r.failure = buf;
    }
  }
}

void writeEvalCsv(const std::string& path, const std::vector<EvalRow>& rows) {
  writeFileAtomically(path, [&](std::ostream& o) {
    o << kHeader << "\n";
    for (EvalRow r : rows) {
      o << quoted(r.source) << "," << r.seed << "," << quoted(r.method) << "," << quoted(r.status);
      for (const double* x : numbers(r)) o << "," << number(*x);
      for (const double x : ratios(r)) o << "," << number(x);
      o << "," << quoted(r.confidentlyWrong()) << "," << (r.failed ? 1 : 0) << ","
        << quoted(r.failure) << "," << r.warnings << "," << (r.wrong_calibration ? 1 : 0) << ","
        << number(r.rest_duration) << "," << quoted(r.block);
      for (const double* x : misdeclarationNumbers(r)) o << "," << number(*x);
      o << "," << count(r.window_samples) << "," << count(r.rest_samples) << ","
        << number(r.ratioGyroBiasZeroRate()) << "\n";
    }
  });
}

std::vector<EvalRow> readEvalCsv(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot open");
  std::string line;
  if (!std::getline(f, line) || line != kHeader)
    throw std::runtime_error(path + ": line 1: not an evaluation CSV header");
  std::vector<EvalRow> rows;
  for (int n = 2; std::getline(f, line); ++n) {
    if (line.empty()) continue;
    const std::string where = path + ": line " + std::to_string(n);
    const auto c = splitCsv(line, where);
    if (c.size() != kColumns)
      throw std::runtime_error(where + ": " + std::to_string(c.size()) + " fields, expected " +
                               std::to_string(kColumns));
    EvalRow r;
    r.source = c[0];
    const auto seed = parseDouble(c[1]);
    if (!seed || !(*seed >= 0 && *seed <= 1e9) || *seed != std::floor(*seed))
      throw std::runtime_error(where + ": seed is not a whole number >= 0: '" + c[1] + "'");
    r.seed = static_cast<int>(*seed);
    r.method = c[2];
    r.status = c[3];
    std::size_t i = 4;
    for (double* x : numbers(r)) *x = parseNumber(c[i++], where);
    for (i = kFirstRatioColumn; i < kConfidentWrongColumn; ++i) parseNumber(c[i], where);
    const std::string& failed = c[kFailedColumn];
    if (failed != "0" && failed != "1") throw std::runtime_error(where + ": failed must be 0 or 1");
    r.failed = failed == "1";
    r.failure = c[kFailureColumn];
    const auto warnings = parseDouble(c[kWarningsColumn]);
    if (!warnings || !(*warnings >= 0 && *warnings <= 1e6) || *warnings != std::floor(*warnings))
      throw std::runtime_error(where + ": warnings is not a whole number >= 0: '" +
                               c[kWarningsColumn] + "'");
    r.warnings = static_cast<int>(*warnings);
    const std::string& wrong = c[kWrongCalibrationColumn];
    if (wrong != "0" && wrong != "1")
      throw std::runtime_error(where + ": wrong_calibration must be 0 or 1");
    r.wrong_calibration = wrong == "1";
    r.rest_duration = parseNumber(c[kRestColumn], where);
    r.block = c[kBlockColumn];
    i = kFirstMisdeclarationColumn;
    for (double* x : misdeclarationNumbers(r)) *x = parseNumber(c[i++], where);
    auto samples = [&](std::size_t column, const char* name) {
      if (c[column].empty()) return -1;
      const auto v = parseDouble(c[column]);
      if (!v || !(*v >= 0 && *v <= 1e9) || *v != std::floor(*v))
        throw std::runtime_error(where + ": " + name + " is not a whole number >= 0: '" +
                                 c[column] + "'");
      return static_cast<int>(*v);
    };
    r.window_samples = samples(kWindowSamplesColumn, "window_samples");
    r.rest_samples = samples(kRestSamplesColumn, "rest_samples");
    parseNumber(c[kZeroRateRatioColumn], where);
    rows.push_back(r);
  }
  return rows;
}

std::string markdownSummary(const std::vector<EvalRow>& rows, const FailureThresholds& th) {
  const auto sources = ordered(rows, [](const EvalRow& r) { return r.source; });
  const auto methods = ordered(rows, [](const EvalRow& r) { return r.method; });
  const Metric metrics[] = {
      {"velocity err [m/s]", &EvalRow::velocity_err, false, th.velocity},
      {"gravity err [deg]", &EvalRow::gravity_err_deg, false, th.gravity_deg},
      {"b_g err [rad/s]", &EvalRow::gyro_bias_err, false, kNoValue},
      {"b_a err [m/s²]", &EvalRow::accel_bias_err, false, kNoValue},
      {"position err [m]", &EvalRow::position_err, false, kNoValue},
      {"time [ms] (mean)", &EvalRow::time_ms, true, kNoValue},
  };
  std::ostringstream o;
  o << "| metric | method |";
  for (const auto& s : sources) o << " " << s << " |";
  o << "\n|---|---|";
  for (std::size_t i = 0; i < sources.size(); ++i) o << "---|";
  o << "\n";
  auto runsOf = [&](const std::string& method, const std::string& source) {
    std::vector<const EvalRow*> out;
    for (const auto& r : rows)
      if (r.method == method && r.source == source) out.push_back(&r);
    return out;
  };
  for (const Metric& m : metrics) {
    for (const auto& method : methods) {
      o << "| " << m.label << " | " << method << " |";
      for (const auto& source : sources) {
        const auto runs = runsOf(method, source);
        double agg = kNoValue, sum = 0;
        int n_values = 0, n_over = 0, n_no_state = 0;
        for (const EvalRow* r : runs) {
          const double x = r->*m.field;
          if (r->status != "ok") ++n_no_state;
          if (std::isnan(x)) continue;
          sum += x;
          ++n_values;
          if (std::isnan(agg) || x > agg) agg = x;
          if (x > m.threshold) ++n_over;
        }
        if (m.mean && n_values > 0) agg = sum / n_values;
        std::string cell;
        if (runs.empty())
          cell = "";
        else if (n_values == 0)
          cell = n_no_state > 0 ? "×" : "–";
        else
          cell = shortNumber(agg);
        if (n_over > 0)
          cell += n_over == static_cast<int>(runs.size())
                      ? " ×"
                      : " ×" + std::to_string(n_over) + "/" + std::to_string(runs.size());
        o << " " << cell << " |";
      }
      o << "\n";
    }
  }
  for (const auto& method : methods) {
    o << "| failed runs | " << method << " |";
    for (const auto& source : sources) {
      const auto runs = runsOf(method, source);
      const auto failed =
          std::count_if(runs.begin(), runs.end(), [](const EvalRow* r) { return r->failed; });
      o << " "
        << (runs.empty() ? std::string()
                         : std::to_string(failed) + "/" + std::to_string(runs.size()))
        << " |";
    }
    o << "\n";
  }
  return o.str();
}

void writeEvalMarkdown(const std::string& path, const std::vector<EvalRow>& rows,
                       const FailureThresholds& th, const std::string& command) {
  writeFileAtomically(path, [&](std::ostream& o) {
    o << "# Initialization errors against ground truth\n\n"
      << "Produced by `" << command << "`.\n\n"
      << "Errors at each method's state time: body-frame velocity, gravity direction in the body "
         "frame, gyro and accelerometer biases, and the displacement over the initialization "
         "window expressed in the body frame at its start. Each cell is the worst over the seeds "
         "(time: the mean wall time of one initialization). A run fails when it gives no state "
         "(`×` alone) or its velocity error exceeds "
      << th.velocity << " m/s or its gravity error " << th.gravity_deg
      << "° (`×` after the value; `×k/n`: k of n seeds).\n\n"
      << markdownSummary(rows, th) << "\n## Against the physical limit\n\n"
      << boundsMarkdown(rows) << "\n## Every run\n\n"
      << "Gravity in brackets: the tilt an unobservable horizontal accelerometer bias implies, "
         "atan(|b_a,h| / g) + "
      << kGravityBoundMarginDeg
      << "°. err/CRB and NEES in the order "
         "velocity, gravity (tilt), b_g, b_a. Noise factors: the true noise over the one the "
         "method was handed (IMU, Doppler); noise declared / true: gyro [rad/s], accelerometer "
         "[m/s²], Doppler [m/s]; offset: the LiDAR-IMU clock offset in the recording, undeclared; "
         "b_g / zero-rate: the gyro-bias error over the bound of an estimator that knows of the "
         "window's rest (the share of the window at rest in brackets).\n\n"
      << "| input | seed | method | status | speed [m/s] | velocity err [m/s] | gravity err "
         "[deg] [b_a limit] | b_g err [rad/s] | b_a err [m/s²] | position err [m] | err/CRB | "
         "NEES | noise factors | noise declared / true | offset [ms] | b_g / zero-rate [rest] | "
         "time [ms] | failure "
         "|\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    auto list = [](const std::vector<double>& xs) {
      std::string out;
      for (const double x : xs) out += (out.empty() ? "" : ", ") + shortNumber(x);
      return out;
    };
    for (const auto& r : rows) {
      o << "| " << r.source << " | " << r.seed << " | " << r.method << " | " << r.status << " | "
        << shortNumber(r.speed) << " | " << shortNumber(r.velocity_err) << " | "
        << shortNumber(r.gravity_err_deg);
      if (!std::isnan(r.gravity_bound_deg)) o << " [" << shortNumber(r.gravity_bound_deg) << "]";
      o << " | " << shortNumber(r.gyro_bias_err) << " | " << shortNumber(r.accel_bias_err) << " | "
        << shortNumber(r.position_err) << " | "
        << (std::isnan(r.ratioVelocity()) ? std::string() : list(ratios(r))) << " | "
        << (std::isnan(r.nees_velocity)
                ? std::string()
                : list({r.nees_velocity, r.nees_tilt, r.nees_gyro_bias, r.nees_accel_bias}))
        << " | ";
      if (!std::isnan(r.imu_noise_factor) || !std::isnan(r.doppler_noise_factor))
        o << list({r.imu_noise_factor, r.doppler_noise_factor});
      o << " | ";
      std::string noise;
      for (const SensorNoise* n : {&r.noise_gyro, &r.noise_accel, &r.noise_doppler})
        if (!std::isnan(n->declared) || !std::isnan(n->truth))
          noise += (noise.empty() ? "" : ", ") + shortNumber(n->declared) + " / " +
                   shortNumber(n->truth);
      o << noise << " | "
        << (std::isnan(r.time_offset_true) ? std::string() : shortNumber(1e3 * r.time_offset_true))
        << " | ";
      if (r.rest_samples > 0)
        o << shortNumber(r.ratioGyroBiasZeroRate()) << " ["
          << shortNumber(static_cast<double>(r.rest_samples) / r.window_samples) << "]";
      o << " | " << shortNumber(r.time_ms) << " | " << (r.failed ? r.failure : std::string())
        << " |\n";
    }
  });
}

std::string EvalRow::confidentlyWrong(const eval::NoticeFloors& floors) const {
  if (status != "ok") return {};
  std::string out;
  auto check = [&](const char* name, double err, double bound, double floor) {
    if (eval::confidentlyWrong(err, bound, floor))
      out += (out.empty() ? "" : ",") + std::string(name);
  };
  check("velocity", velocity_err, crb_velocity, floors.velocity);
  check("gravity", gravity_err_deg, crb_gravity_deg, floors.gravity_deg);
  check("b_g", gyro_bias_err, crb_gyro_bias, floors.gyro_bias);
  check("b_a", accel_bias_err, crb_accel_bias, floors.accel_bias);
  return out;
}

const std::vector<std::string>& statusNames() {
  static const std::vector<std::string> kNames = [] {
    std::vector<std::string> n;
    for (const InitStatus s : {InitStatus::Ok, InitStatus::NotEnoughData, InitStatus::NoDoppler,
                               InitStatus::DegenerateGeometry, InitStatus::SolverFailed,
                               InitStatus::AmbiguousMotion, InitStatus::InconsistentData})
      n.emplace_back(toString(s));
    return n;
  }();
  return kNames;
}

double quantile(std::vector<double> values, double p) {
  if (values.empty()) return kNoValue;
  std::sort(values.begin(), values.end());
  const double pos = std::clamp(p, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  const double u = pos - static_cast<double>(lo);
  if (u == 0) return values[lo];
  return (1 - u) * values[lo] + u * values[hi];
}

namespace {

/// a < b with the numbers in them compared by value ("imu×0.5" < "imu×2" < "imu×16").
bool naturalLess(const std::string& a, const std::string& b) {
  auto isNumber = [](const std::string& s, std::size_t i) {
    return std::isdigit(static_cast<unsigned char>(s[i])) != 0;
  };
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (isNumber(a, i) && isNumber(b, j)) {
      char* end_a = nullptr;
      char* end_b = nullptr;
      const double x = std::strtod(a.c_str() + i, &end_a);
      const double y = std::strtod(b.c_str() + j, &end_b);
      if (x != y) return x < y;
      i = static_cast<std::size_t>(end_a - a.c_str());
      j = static_cast<std::size_t>(end_b - b.c_str());
      continue;
    }
    if (a[i] != b[j]) return a[i] < b[j];
    ++i;
    ++j;
  }
  return a.size() - i < b.size() - j;
}

/// The summary of one method's runs of one block.
MethodSummary summarizeBlock(const std::vector<EvalRow>& rows, const std::string& method,
                             const std::string& block, const eval::NoticeFloors& floors) {
  const auto& names = statusNames();
  const double chi2[4] = {eval::kChi2Quantile999Dof3, eval::kChi2Quantile999Dof2,
                          eval::kChi2Quantile999Dof3, eval::kChi2Quantile999Dof3};
  MethodSummary m;
  m.method = method;
  m.block = block;
  m.status_counts.assign(names.size() + 1, 0);
  std::vector<double> ratio[4], zero_rate_ratio;
  for (const EvalRow& r : rows) {
    if (r.method != method || r.block != block) continue;
    ++m.runs;
    const auto it = std::find(names.begin(), names.end(), r.status);
    ++m.status_counts[static_cast<std::size_t>(it - names.begin())];
    if (r.wrong_calibration) {
      ++m.wrong_calibration_runs;
      if (r.status != "ok") continue;
      ++m.wrong_calibration_ok;
      if (r.confidentlyWrong(floors).empty()) continue;
      ++(r.warnings > 0 ? m.wrong_calibration_flagged : m.wrong_calibration_plain_wrong);
      continue;
    }
    if (r.status != "ok") continue;
    const std::vector<double> rr = ratios(r);
    if (!std::isnan(rr[0])) {
      ++m.with_bound;
      for (int q = 0; q < 4; ++q)
        if (!std::isnan(rr[static_cast<std::size_t>(q)]))
          ratio[q].push_back(rr[static_cast<std::size_t>(q)]);
    }
    const double nees[4] = {r.nees_velocity, r.nees_tilt, r.nees_gyro_bias, r.nees_accel_bias};
    if (!std::isnan(nees[0])) {
      ++m.with_nees;
      for (int q = 0; q < 4; ++q)
        if (nees[q] > chi2[q]) ++m.nees_above[q];
    }
    const double own[4] = {r.sigma_velocity, r.sigma_gravity_deg, r.sigma_gyro_bias,
                           r.sigma_accel_bias};
    const double bound[4] = {r.crb_velocity, r.crb_gravity_deg, r.crb_gyro_bias, r.crb_accel_bias};
    bool compared = false;
    for (int q = 0; q < 4 && !(r.rest_duration > 0); ++q) {
      if (!std::isfinite(own[q]) || !std::isfinite(bound[q])) continue;
      compared = true;
      if (own[q] < kOwnSigmaBelowBound * bound[q]) ++m.sigma_below_bound[q];
    }
    if (compared) ++m.with_sigma;
    if (!r.confidentlyWrong(floors).empty()) ++m.confident_wrong;
    const double zr = r.ratioGyroBiasZeroRate();
    if (r.staticWindow() && !std::isnan(zr)) {
      ++m.static_starts;
      zero_rate_ratio.push_back(zr);
      if (zr > eval::kConfidentWrongRatio) ++m.static_gyro_bias_above_zero_rate;
    }
    const SensorNoise* noise[3] = {&r.noise_gyro, &r.noise_accel, &r.noise_doppler};
    for (int q = 0; q < 3; ++q) {
      const SensorNoise& n = *noise[q];
      if (!(n.reported_rel_sigma <= kReportedNoiseResolved) || !(n.truth > 0) ||
          std::isnan(n.reported))
        continue;
      ++m.noise_resolved[q];
      if (std::abs(n.reported / n.truth - 1) <= kReportedNoiseTolerance) ++m.noise_within[q];
    }
    if (std::isfinite(r.time_offset_reported) && r.time_offset_reported_sigma > 0 &&
        std::isfinite(r.time_offset_true)) {
      ++m.time_offset_reported;
      if (std::abs(r.time_offset_reported - r.time_offset_true) <= 3 * r.time_offset_reported_sigma)
        ++m.time_offset_within;
    }
  }
  for (int q = 0; q < 4; ++q) {
    m.ratio_median[q] = quantile(ratio[q], 0.5);
    m.ratio_p95[q] = quantile(ratio[q], 0.95);
  }
  m.zero_rate_ratio_median = quantile(zero_rate_ratio, 0.5);
  m.zero_rate_ratio_p95 = quantile(zero_rate_ratio, 0.95);
  return m;
}

}  // namespace

std::vector<MethodSummary> summarize(const std::vector<EvalRow>& rows,
                                     const eval::NoticeFloors& floors) {
  std::vector<MethodSummary> out;
  for (const auto& method : ordered(rows, [](const EvalRow& r) { return r.method; })) {
    std::vector<std::string> blocks;
    for (const EvalRow& r : rows)
      if (r.method == method && std::find(blocks.begin(), blocks.end(), r.block) == blocks.end())
        blocks.push_back(r.block);
    std::sort(blocks.begin(), blocks.end(), naturalLess);
    for (const auto& block : blocks) out.push_back(summarizeBlock(rows, method, block, floors));
  }
  return out;
}

namespace {

/// One table row per method: counts[q] of `of` runs per quantity, as "n/of (share %)" ("–"
/// without runs).
void shareRows(std::ostream& o, const std::vector<MethodSummary>& summaries,
               int (MethodSummary::*counts)[4], int MethodSummary::*of) {
  for (const auto& m : summaries) {
    o << "| " << m.label() << " |";
    for (int q = 0; q < 4; ++q) {
      char buf[64];
      const int n = (m.*counts)[q], total = m.*of;
      if (total == 0)
        std::snprintf(buf, sizeof(buf), "–");
      else
        std::snprintf(buf, sizeof(buf), "%d/%d (%.1f %%)", n, total, 100.0 * n / total);
      o << " " << buf << " |";
    }
    o << "\n";
  }
}

}  // namespace

std::string boundsMarkdown(const std::vector<EvalRow>& rows, const eval::NoticeFloors& floors,
                           std::size_t max_listed) {
  const auto summaries = summarize(rows, floors);
  std::ostringstream o;
  o << "Error / Cramér-Rao bound of each ok run (bound: the square root of the trace of the "
       "posterior CRB covariance of body velocity, gravity direction (2 dof), b_g and b_a at the "
       "run's state time, for that run's window, data and the estimator's bias priors; an "
       "efficient estimator has a median near 0.9 and a 95th percentile near 1.6), median and "
       "95th percentile over the ok runs with a bound. Confident wrong: ok runs more than "
    << eval::kConfidentWrongRatio << "× their bound on a quantity whose error is also above "
    << shortNumber(floors.velocity) << " m/s, " << shortNumber(floors.gravity_deg) << "°, "
    << shortNumber(floors.gyro_bias) << " rad/s or " << shortNumber(floors.accel_bias)
    << " m/s².\n\n";
  o << "| method | ok / runs | velocity median | p95 | gravity median | p95 | b_g median | p95 | "
       "b_a median | p95 | confident wrong |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& m : summaries) {
    o << "| " << m.label() << " | " << m.status_counts[0] << " / " << m.runs << " |";
    for (int q = 0; q < 4; ++q)
      o << " " << shortNumber(m.ratio_median[q]) << " | " << shortNumber(m.ratio_p95[q]) << " |";
    o << " " << m.confident_wrong << " |\n";
  }
  o << "\nShare of the ok runs with a NEES of the state's own covariance above the 99.9 % "
       "chi-square quantile (velocity, b_g, b_a: 3 dof, "
    << eval::kChi2Quantile999Dof3 << "; tilt: 2 dof, " << eval::kChi2Quantile999Dof2
    << "; a consistent estimator: 0.1 %).\n\n"
    << "| method | velocity | tilt | b_g | b_a |\n|---|---|---|---|---|\n";
  shareRows(o, summaries, &MethodSummary::nees_above, &MethodSummary::with_nees);
  o << "\nStatic starts: the ok runs whose window is at rest throughout (by the truth). Their "
       "gyro-bias error against the zero-rate bound, the bound of an estimator that knows of the "
       "rest (sqrt(sum_i 1 / (N / sigma_i² + 1 / sigma_0²)) over the N samples at rest, "
       "sigma_i the true gyro noise per axis, sigma_0 the prior; sigma sqrt(3 / N) without a "
       "prior): above "
    << eval::kConfidentWrongRatio
    << "× it, the rest was not used as it could be.\n\n| method | static starts with b_g error "
       "> "
    << eval::kConfidentWrongRatio
    << "× the zero-rate bound | b_g error / zero-rate bound median | p95 |\n|---|---|---|---|\n";
  for (const auto& m : summaries) {
    o << "| " << m.label() << " | ";
    if (m.static_starts == 0)
      o << "– |";
    else
      o << m.static_gyro_bias_above_zero_rate << "/" << m.static_starts << " |";
    o << " " << shortNumber(m.zero_rate_ratio_median) << " | " << shortNumber(m.zero_rate_ratio_p95)
      << " |\n";
  }
  const bool reported = std::any_of(summaries.begin(), summaries.end(), [](const MethodSummary& m) {
    return m.noise_resolved[0] + m.noise_resolved[1] + m.noise_resolved[2] +
               m.time_offset_reported >
           0;
  });
  if (!reported) {
    o << "\nNo method reports the noise or the clock offset it used (the CSV's "
         "noise_*_reported and time_offset_reported columns are empty).\n";
  } else {
    o << "\nThe noise each method reports against the truth (the RMS over the axes of the "
         "simulated per-axis sigmas): the runs whose reported noise is within "
      << 100 * kReportedNoiseTolerance
      << " % of the truth, of the ok runs whose report claims a relative sigma of at most "
      << 100 * kReportedNoiseResolved
      << " % (enough samples to tell); the clock offset: within 3 of its sigmas.\n\n"
      << "| method | gyro | accel | Doppler | time offset |\n|---|---|---|---|---|\n";
    auto share = [](int n, int of) {
      if (of == 0) return std::string("–");
      char buf[64];
      std::snprintf(buf, sizeof(buf), "%d/%d (%.1f %%)", n, of, 100.0 * n / of);
      return std::string(buf);
    };
    for (const auto& m : summaries) {
      o << "| " << m.label() << " |";
      for (int q = 0; q < 3; ++q) o << " " << share(m.noise_within[q], m.noise_resolved[q]) << " |";
      o << " " << share(m.time_offset_within, m.time_offset_reported) << " |\n";
    }
  }
  o << "\nShare of the ok runs whose own sigma (the square root of the trace of each block of "
       "the state's covariance) is below "
    << kOwnSigmaBelowBound
    << " of the bound: a covariance that claims more than the data hold (0 for a consistent "
       "estimator). Runs that used the knowledge of rest (zero velocity and rate, or the rate "
       "alone, while the IMU showed rest) are left out: the bound does not know of it.\n\n| method "
       "| velocity | gravity "
       "| b_g | b_a |\n|---|---|---|---|---|\n";
  shareRows(o, summaries, &MethodSummary::sigma_below_bound, &MethodSummary::with_sigma);
  const auto& names = statusNames();
  o << "\nStatus of every run.\n\n| method |";
  for (const auto& n : names) o << " " << n << " |";
  const bool other = std::any_of(summaries.begin(), summaries.end(), [&](const MethodSummary& m) {
    return m.status_counts.back() > 0;
  });
  if (other) o << " other |";
  o << "\n|---|";
  for (std::size_t i = 0; i < names.size() + (other ? 1 : 0); ++i) o << "---|";
  o << "\n";
  for (const auto& m : summaries) {
    o << "| " << m.label() << " |";
    for (std::size_t i = 0; i < names.size() + (other ? 1 : 0); ++i)
      o << " " << m.status_counts[i] << " |";
    o << "\n";
  }
  if (std::any_of(summaries.begin(), summaries.end(),
                  [](const MethodSummary& m) { return m.wrong_calibration_runs > 0; })) {
    o << "\nRuns handed a wrong calibration (an undeclared LiDAR-IMU time offset or extrinsics "
         "error; not in the tables above): how many gave a state, and of those more than 3× "
         "their bound (above the floors) how many said so with a warning and how many were a "
         "plain ok.\n\n| method | runs | ok | wrong, flagged | wrong, plain ok |\n"
         "|---|---|---|---|---|\n";
    for (const auto& m : summaries)
      o << "| " << m.label() << " | " << m.wrong_calibration_runs << " | " << m.wrong_calibration_ok
        << " | " << m.wrong_calibration_flagged << " | " << m.wrong_calibration_plain_wrong
        << " |\n";
  }
  // The bound itself per input (median over the seeds), for the first method's windows.
  if (!rows.empty()) {
    const std::string& first = rows.front().method;
    const auto sources = ordered(rows, [](const EvalRow& r) { return r.source; });
    const struct {
      const char* label;
      double EvalRow::*field;
    } kBounds[] = {{"velocity [m/s]", &EvalRow::crb_velocity},
                   {"gravity [deg]", &EvalRow::crb_gravity_deg},
                   {"b_g [rad/s]", &EvalRow::crb_gyro_bias},
                   {"b_a [m/s²]", &EvalRow::crb_accel_bias}};
    o << "\nThe bound per input (median over the seeds, " << first << "'s windows):\n\n"
      << "| CRB |";
    for (const auto& s : sources) o << " " << s << " |";
    o << "\n|---|";
    for (std::size_t i = 0; i < sources.size(); ++i) o << "---|";
    o << "\n";
    for (const auto& b : kBounds) {
      o << "| " << b.label << " |";
      for (const auto& s : sources) {
        std::vector<double> v;
        for (const EvalRow& r : rows)
          if (r.method == first && r.source == s && !std::isnan(r.*b.field))
            v.push_back(r.*b.field);
        o << " " << shortNumber(quantile(v, 0.5)) << " |";
      }
      o << "\n";
    }
  }
  o << "\nConfident wrong answers:";
  bool any = false;
  std::map<std::string, std::size_t> listed, unlisted;
  for (const EvalRow& r : rows) {
    const std::string wrong = r.confidentlyWrong(floors);
    if (wrong.empty() || r.wrong_calibration) continue;
    if (listed[r.method] >= max_listed) {
      ++unlisted[r.method];
      continue;
    }
    ++listed[r.method];
    if (!any)
      o << "\n\n| input | seed | method | quantities | err/CRB (v, g, b_g, b_a) |\n"
           "|---|---|---|---|---|\n";
    any = true;
    o << "| " << r.source << " | " << r.seed << " | "
      << (r.block.empty() ? r.method : r.method + " · " + r.block) << " | " << wrong << " | ";
    const auto rr = ratios(r);
    for (std::size_t i = 0; i < rr.size(); ++i) o << (i ? ", " : "") << shortNumber(rr[i]);
    o << " |\n";
  }
  for (const auto& [method, n] : unlisted) o << "| … | | " << method << " | " << n << " more | |\n";
  if (!any) o << " none.\n";
  return o.str();
}

void writeSummaryCsv(const std::string& path, const std::vector<EvalRow>& rows,
                     const eval::NoticeFloors& floors) {
  const auto summaries = summarize(rows, floors);
  writeFileAtomically(path, [&](std::ostream& o) {
    o << "method,block,runs";
    for (const auto& n : statusNames()) o << "," << n;
    o << ",other_status,runs_with_bound";
    for (const char* q : {"velocity", "gravity", "gyro_bias", "accel_bias"})
      o << ",ratio_" << q << "_median,ratio_" << q << "_p95";
    o << ",runs_with_nees";
    for (const char* q : {"velocity", "tilt", "gyro_bias", "accel_bias"})
      o << ",nees_" << q << "_above_chi2_999";
    o << ",confident_wrong,wrong_calibration_runs,wrong_calibration_ok,"
         "wrong_calibration_flagged,wrong_calibration_plain_wrong,static_starts,"
         "static_gyro_bias_above_3x_zero_rate,ratio_gyro_bias_zero_rate_median,"
         "ratio_gyro_bias_zero_rate_p95";
    for (const char* q : {"gyro", "accel", "doppler"})
      o << ",noise_" << q << "_resolved,noise_" << q << "_within_20pct";
    o << ",time_offset_reported,time_offset_within_3sigma\n";
    for (const auto& m : summaries) {
      o << quoted(m.method) << "," << quoted(m.block) << "," << m.runs;
      for (const int c : m.status_counts) o << "," << c;
      o << "," << m.with_bound;
      for (int q = 0; q < 4; ++q)
        o << "," << number(m.ratio_median[q]) << "," << number(m.ratio_p95[q]);
      o << "," << m.with_nees;
      for (const int c : m.nees_above) o << "," << c;
      o << "," << m.confident_wrong << "," << m.wrong_calibration_runs << ","
        << m.wrong_calibration_ok << "," << m.wrong_calibration_flagged << ","
        << m.wrong_calibration_plain_wrong << "," << m.static_starts << ","
        << m.static_gyro_bias_above_zero_rate << "," << number(m.zero_rate_ratio_median) << ","
        << number(m.zero_rate_ratio_p95);
      for (int q = 0; q < 3; ++q) o << "," << m.noise_resolved[q] << "," << m.noise_within[q];
      o << "," << m.time_offset_reported << "," << m.time_offset_within << "\n";
    }
  });
}

std::optional<double> parseDouble(const std::string& s) {
  std::size_t used = 0;
  double x = 0;
  try {
    x = std::stod(s, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (used != s.size()) return std::nullopt;
  return x;
}

}  // namespace freeinit::report
