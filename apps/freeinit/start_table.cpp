#include "start_table.h"

#include <freeinit/io/atomic_file.h>
#include <freeinit/io/number_format.h>
#include <freeinit/report/plot.h>
#include <freeinit/rotation.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace freeinit::apps {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

/// Covariances of the gauge-free quantities, to first order in the state's error (right
/// perturbation dtheta of R_wb): dv_b = R^T dv_w + [v_b]x dtheta; the tilt error is dtheta
/// projected on the plane orthogonal to gravity in b; the biases as they are.
struct GaugeFreeCov {
  Mat3 vel_b, tilt, gyro_bias, accel_bias;
};

GaugeFreeCov gaugeFreeCov(const InitialState& s) {
  GaugeFreeCov c;
  const Cov18& P = s.cov;
  Eigen::Matrix<double, 3, 18> A = Eigen::Matrix<double, 3, 18>::Zero();
  A.block<3, 3>(0, kVel) = s.q_wb.toRotationMatrix().transpose();
  A.block<3, 3>(0, kTheta) = skew(s.v_b());
  c.vel_b = A * P * A.transpose();
  const Vec3 g_hat = s.g_b().normalized();
  const Mat3 Pt = Mat3::Identity() - g_hat * g_hat.transpose();
  c.tilt = Pt * P.block<3, 3>(kTheta, kTheta) * Pt;
  c.gyro_bias = P.block<3, 3>(kBg, kBg);
  c.accel_bias = P.block<3, 3>(kBa, kBa);
  return c;
}

/// e^T C^+ e over the numerically non-zero eigen-directions of C.
double nees(const Vec3& e, const Mat3& C) {
  const Eigen::SelfAdjointEigenSolver<Mat3> es(C);
  const double max_ev = es.eigenvalues().maxCoeff();
  double sum = 0;
  for (int i = 0; i < 3; ++i) {
    const double ev = es.eigenvalues()(i);
    if (ev <= max_ev * 1e-9) continue;
    const double proj = es.eigenvectors().col(i).dot(e);
    sum += proj * proj / ev;
  }
  return sum;
}

double rms(const Mat3& C) { return std::sqrt(std::max(0.0, C.trace())); }

std::string csvQuote(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (const char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

}  // namespace

StateNees stateNees(const InitialState& s, const std::vector<app_support::TruthSample>& truth) {
  StateNees n;
  n.errors = app_support::compareWithTruth(s, truth);
  const app_support::TruthSample gt = *app_support::truthAt(truth, s.timestamp);
  const Mat3 R_bw = gt.q_wb.conjugate().toRotationMatrix();
  const GaugeFreeCov c = gaugeFreeCov(s);
  n.vel_b = nees(s.v_b() - R_bw * gt.v_w, c.vel_b);
  n.tilt = nees(s.g_b().normalized().cross((R_bw * gt.g_w).normalized()), c.tilt);
  n.gyro_bias = nees(s.b_g - gt.b_g, c.gyro_bias);
  n.accel_bias = nees(s.b_a - gt.b_a, c.accel_bias);
  return n;
}

std::string startFolderName(double offset, int decimals) {
  // Rounded as folderDecimals() tells names apart: the offset in units of 10^-decimals s.
  long long scale = 1;
  for (int i = 0; i < decimals; ++i) scale *= 10;
  const long long units = std::llround(offset * static_cast<double>(scale));
  const long long magnitude = units < 0 ? -units : units;
  std::ostringstream os;
  os << "start_" << (units < 0 ? "-" : "") << std::setw(4) << std::setfill('0') << magnitude / scale
     << "." << std::setw(decimals) << magnitude % scale;
  return os.str();
}

StartRow startRow(std::size_t index, double start, double first, const app_support::InitSession& s,
                  bool at_end, const std::vector<app_support::TruthSample>& truth, int decimals) {
  StartRow row;
  row.index = index;
  row.start = start;
  row.start_offset = start - first;
  if (s.failed()) {
    row.status = "input_error";
    for (const auto& e : s.errors()) row.message += (row.message.empty() ? "" : "; ") + e;
  } else if (!s.ready() || (at_end && s.result().state.status == InitStatus::NotEnoughData)) {
    // The file ends before the window closes: listed, no outputs.
    row.status = toString(InitStatus::NotEnoughData);
    std::ostringstream why;
    why << std::setprecision(3) << "the recording ends " << s.lastTime().value_or(start) - start
        << " s after this start, before a window closes";
    row.message = why.str();
  } else {
    const InitResult& r = s.result();
    row.state = r.state;
    row.status = toString(r.state.status);
    row.message = r.state.message;
    if (r.state.ok()) {
      row.window_begin = r.trajectory.front().t;
      if (!truth.empty() && app_support::truthAt(truth, r.state.timestamp))
        row.truth = stateNees(r.state, truth);
    }
    row.folder = startFolderName(row.start_offset, decimals);
  }
  return row;
}

StartRow unreachedStartRow(std::size_t index, double start, double first,
                           const std::optional<std::string>& read_error) {
  StartRow row;
  row.index = index;
  row.start = start;
  row.start_offset = start - first;
  row.status = read_error ? "unreadable" : toString(InitStatus::NotEnoughData);
  row.message = read_error ? *read_error : "no record at or after this start";
  return row;
}

bool startFailed(const StartRow& row, bool at_end) {
  const bool cut_by_end = at_end && row.status == toString(InitStatus::NotEnoughData);
  return row.status != toString(InitStatus::Ok) && !cut_by_end;
}

void printStartRow(std::ostream& log, const StartRow& row, const std::string& out_dir) {
  log << "Start " << row.index << " at " << std::fixed << std::setprecision(3) << row.start_offset
      << " s: " << row.status << std::defaultfloat
      << (row.message.empty() ? "" : " (" + row.message + ")");
  if (row.state && row.state->ok())
    log << ", |v_b| " << std::setprecision(4) << row.state->v_b().norm() << " m/s"
        << std::defaultfloat;
  if (row.truth)
    log << ", errors: velocity " << row.truth->errors.velocity << " m/s, gravity "
        << row.truth->errors.gravity_deg << " deg";
  log << (row.folder.empty() ? "" : " -> " + (std::filesystem::path(out_dir) / row.folder).string())
      << "\n";
}

void writeStartTableCsv(const std::string& path, const std::vector<StartRow>& rows) {
  writeFileAtomically(path, [&](std::ostream& o) {
    o << "index,start_offset_s,start_unix,folder,status,message,timestamp,window_s,"
         "v_b_x,v_b_y,v_b_z,g_b_x,g_b_y,g_b_z,b_g_x,b_g_y,b_g_z,b_a_x,b_a_y,b_a_z,"
         "sigma_velocity,sigma_tilt_deg,sigma_gyro_bias,sigma_accel_bias,"
         "err_velocity,err_gravity_deg,err_gyro_bias,err_accel_bias,"
         "nees_velocity,nees_tilt,nees_gyro_bias,nees_accel_bias\n";
    o << std::setprecision(9);
    for (const auto& r : rows) {
      o << r.index << "," << std::fixed << std::setprecision(6) << r.start_offset << "," << r.start
        << std::defaultfloat << std::setprecision(9) << "," << r.folder << "," << r.status << ","
        << csvQuote(r.message) << ",";
      if (r.state && r.state->ok()) {
        const InitialState& s = *r.state;
        const GaugeFreeCov c = gaugeFreeCov(s);
        o << std::fixed << std::setprecision(6) << s.timestamp << std::defaultfloat
          << std::setprecision(9) << "," << s.timestamp - r.window_begin;
        for (const Vec3& v : {s.v_b(), s.g_b(), s.b_g, s.b_a})
          o << "," << v.x() << "," << v.y() << "," << v.z();
        o << "," << rms(c.vel_b) << "," << rms(c.tilt) * kRadToDeg << "," << rms(c.gyro_bias) << ","
          << rms(c.accel_bias);
      } else {
        o << std::string(22, ',');
      }
      if (r.truth) {
        const auto& t = *r.truth;
        o << "," << t.errors.velocity << "," << t.errors.gravity_deg << "," << t.errors.gyro_bias
          << "," << t.errors.accel_bias << "," << t.vel_b << "," << t.tilt << "," << t.gyro_bias
          << "," << t.accel_bias;
      } else {
        o << std::string(8, ',');
      }
      o << "\n";
    }
  });
}

void writeStartTableMarkdown(const std::string& path, const std::vector<StartRow>& rows,
                             const std::string& rawlog, const std::string& command) {
  const bool truth =
      std::any_of(rows.begin(), rows.end(), [](const StartRow& r) { return r.truth.has_value(); });
  writeFileAtomically(path, [&](std::ostream& o) {
    o << "# Free-Init along " << rawlog << "\n\n`" << command << "`\n\n"
      << "One initialization per start (records from the start on); errors against the ground "
         "truth beside the rawlog"
      << (truth ? "" : " (none here)")
      << ", sigma = sqrt(trace) of the reported covariance of each quantity, NEES from that "
         "covariance (velocity, gyro and accel bias 3 dof, tilt 2 dof).\n\n";
    o << "| start [s] | folder | status | |v_b| [m/s] | velocity err (sigma) [m/s] | gravity err "
         "(sigma) [deg] | b_g err (sigma) [rad/s] | b_a err (sigma) [m/s^2] | NEES v / tilt / "
         "b_g / b_a |\n|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : rows) {
      o << "| " << std::fixed << std::setprecision(3) << r.start_offset << std::defaultfloat
        << " | " << (r.folder.empty() ? "-" : r.folder) << " | " << r.status
        << (r.message.empty() ? "" : " (" + r.message + ")") << " | ";
      if (!(r.state && r.state->ok())) {
        o << "| | | | | |\n";
        continue;
      }
      const GaugeFreeCov c = gaugeFreeCov(*r.state);
      const auto cell = [&](std::optional<double> err, double sigma) {
        return (err ? formatSignificant(*err, 3) : std::string("-")) + " (" +
               formatSignificant(sigma, 2) + ")";
      };
      const auto& t = r.truth;
      o << formatSignificant(r.state->v_b().norm(), 4) << " | "
        << cell(t ? std::optional(t->errors.velocity) : std::nullopt, rms(c.vel_b)) << " | "
        << cell(t ? std::optional(t->errors.gravity_deg) : std::nullopt, rms(c.tilt) * kRadToDeg)
        << " | " << cell(t ? std::optional(t->errors.gyro_bias) : std::nullopt, rms(c.gyro_bias))
        << " | " << cell(t ? std::optional(t->errors.accel_bias) : std::nullopt, rms(c.accel_bias))
        << " | "
        << (t ? formatSignificant(t->vel_b, 2) + " / " + formatSignificant(t->tilt, 2) + " / " +
                    formatSignificant(t->gyro_bias, 2) + " / " + formatSignificant(t->accel_bias, 2)
              : std::string("-"))
        << " |\n";
    }
  });
}

void renderStartPlot(const std::string& png, const std::vector<StartRow>& rows, int width,
                     int height) {
  struct Quantity {
    const char* title;
    const char* unit;
  };
  const Quantity q[4] = {{"body velocity", "m/s"},
                         {"gravity direction (tilt)", "deg"},
                         {"gyro bias", "rad/s"},
                         {"accelerometer bias", "m/s^2"}};
  std::vector<cv::Mat> panels;
  for (int k = 0; k < 4; ++k) {
    report::Series err, sigma;
    err.label = "error w.r.t. ground truth";
    err.style = report::Series::Style::Markers;
    err.color = plot::palette(0);
    err.thickness = 4;
    sigma.label = "1 sigma (reported)";
    sigma.color = plot::palette(1);
    for (const auto& r : rows) {
      if (!(r.state && r.state->ok())) continue;
      const GaugeFreeCov c = gaugeFreeCov(*r.state);
      const double s[4] = {rms(c.vel_b), rms(c.tilt) * kRadToDeg, rms(c.gyro_bias),
                           rms(c.accel_bias)};
      sigma.x.push_back(r.start_offset);
      sigma.y.push_back(s[k]);
      if (r.truth) {
        const auto& e = r.truth->errors;
        const double v[4] = {e.velocity, e.gravity_deg, e.gyro_bias, e.accel_bias};
        err.x.push_back(r.start_offset);
        err.y.push_back(v[k]);
      }
    }
    report::Plot plot;
    plot.title = q[k].title;
    plot.x_label = "start [s after the first record]";
    plot.y_label = q[k].unit;
    if (!err.x.empty()) plot.add(err);
    plot.add(sigma);
    panels.push_back(plot.render(width / 2, height / 2));
  }
  report::savePng(png, report::tile(panels, 2));
}

}  // namespace freeinit::apps
