#include <freeinit/atomic_file.h>
#include <freeinit/report/eval_table.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace freeinit::report {
namespace {

// Column order of the CSV; readEvalCsv requires exactly this header.
const char* const kHeader =
    "source,seed,method,status,speed_mps,velocity_err_mps,gravity_err_deg,gravity_bound_deg,"
    "gyro_bias_err_radps,accel_bias_err_mps2,position_err_m,time_ms,failed,failure";
constexpr std::size_t kColumns = 14;

/// The numeric fields of a row, in CSV order after "status".
std::vector<double*> numbers(EvalRow& r) {
  return {&r.speed,         &r.velocity_err,   &r.gravity_err_deg, &r.gravity_bound_deg,
          &r.gyro_bias_err, &r.accel_bias_err, &r.position_err,    &r.time_ms};
}

std::string quoted(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += (c == '"') ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

/// %.10g (round trip to 1e-10 relative), empty for NaN.
std::string number(double x) {
  if (std::isnan(x)) return "";
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
      o << "," << (r.failed ? 1 : 0) << "," << quoted(r.failure) << "\n";
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
    if (c[12] != "0" && c[12] != "1") throw std::runtime_error(where + ": failed must be 0 or 1");
    r.failed = c[12] == "1";
    r.failure = c[13];
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
      << markdownSummary(rows, th) << "\n## Every run\n\n"
      << "| input | seed | method | status | speed [m/s] | velocity err [m/s] | gravity err "
         "[deg] (bound) | b_g err [rad/s] | b_a err [m/s²] | position err [m] | time [ms] | "
         "failure |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : rows) {
      o << "| " << r.source << " | " << r.seed << " | " << r.method << " | " << r.status << " | "
        << shortNumber(r.speed) << " | " << shortNumber(r.velocity_err) << " | "
        << shortNumber(r.gravity_err_deg);
      if (!std::isnan(r.gravity_bound_deg)) o << " (" << shortNumber(r.gravity_bound_deg) << ")";
      o << " | " << shortNumber(r.gyro_bias_err) << " | " << shortNumber(r.accel_bias_err) << " | "
        << shortNumber(r.position_err) << " | " << shortNumber(r.time_ms) << " | "
        << (r.failed ? r.failure : std::string()) << " |\n";
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
