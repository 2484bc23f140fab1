// The evaluation report: CSV written and read back, failure marking, the paper-layout summary,
// the summaries per block of misdeclaration, the displacement error, the job pool, the PNG
// writer, the methods run on equal terms and freeinit-eval's app class (its command line, runs
// paired across noise factors, a tiny run).
#include <freeinit/eval/state_errors.h>
#include <freeinit/report/eval_table.h>
#include <freeinit/report/methods.h>
#include <freeinit/report/plot.h>
#include <freeinit/rotation.h>
#include <freeinit/sim/presets.h>
#include <freeinit/sim/simulator.h>
#include <gtest/gtest.h>
#include <pthread.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "eval_app.h"
#include "test_sim_recording_hash.h"

namespace freeinit::report {
namespace {

std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("freeinit_test_" + name)).string();
}

std::vector<EvalRow> sampleRows() {
  EvalRow ok;
  ok.source = "dyna_01";
  ok.seed = 1;
  ok.method = "free-init";
  ok.speed = 1.2345678901;
  ok.velocity_err = 0.0123456789;
  ok.gravity_err_deg = 0.25;
  ok.gravity_bound_deg = 0.97;
  ok.gyro_bias_err = 1.5e-4;
  ok.accel_bias_err = 0.039;
  ok.position_err = 0.004;
  ok.time_ms = 21.5;
  ok.crb_velocity = 0.002;
  ok.crb_gravity_deg = 0.14;
  ok.crb_gyro_bias = 0.0096;
  ok.crb_accel_bias = std::numeric_limits<double>::infinity();  // unobservable
  ok.nees_velocity = 2.5;
  ok.nees_tilt = 14.0;  // above the 2-dof 99.9 % quantile
  ok.nees_gyro_bias = 0.7;
  ok.nees_accel_bias = 1.1;
  ok.sigma_velocity = 0.0021;
  ok.sigma_gravity_deg = 0.13;  // below 0.95 of its bound: claims more than the data hold
  ok.sigma_gyro_bias = 0.0101;
  ok.sigma_accel_bias = 0.05;  // against an infinite bound: not compared
  ok.rest_duration = 0.25;
  ok.block = "imu×4 doppler≈×0.5";
  ok.imu_noise_factor = 4;
  ok.doppler_noise_factor = 0.61;
  ok.noise_gyro = {0.0005, 0.0021, kNoValue, kNoValue};
  ok.noise_accel = {0.005, 0.019, 0.0195, 0.06};  // as an estimator will report it
  ok.noise_doppler = {0.049, 0.03, kNoValue, kNoValue};
  ok.time_offset_true = -0.0081;
  ok.time_offset_reported = -0.0079;
  ok.time_offset_reported_sigma = 0.0004;
  ok.crb_gyro_bias_zero_rate = 0.00031;
  ok.window_samples = 101;
  ok.rest_samples = 40;
  EvalRow fast = ok;
  fast.method = "fast-lio2";
  fast.velocity_err = 1.22;  // over the 0.2 m/s threshold
  EvalRow tilted = ok;
  tilted.seed = 2;
  tilted.gravity_err_deg = 3.5;  // over the 2 deg threshold
  tilted.warnings = 2;
  tilted.wrong_calibration = true;
  EvalRow none;
  none.source = "a dir, with \"quotes\"/x.rawlog";  // needs CSV quoting
  none.method = "dlio";
  none.status = "not_enough_data";
  return {ok, fast, tilted, none};
}

TEST(EvalTable, MarksFailuresByStatusAndThresholds) {
  auto rows = sampleRows();
  markFailures(rows, FailureThresholds{});
  EXPECT_FALSE(rows[0].failed);
  EXPECT_TRUE(rows[1].failed);
  EXPECT_NE(rows[1].failure.find("velocity"), std::string::npos) << rows[1].failure;
  EXPECT_TRUE(rows[2].failed);
  EXPECT_NE(rows[2].failure.find("gravity"), std::string::npos) << rows[2].failure;
  EXPECT_TRUE(rows[3].failed);
  EXPECT_NE(rows[3].failure.find("not_enough_data"), std::string::npos);
  // Looser thresholds: only the run without a state fails.
  markFailures(rows, FailureThresholds{2.0, 5.0});
  EXPECT_FALSE(rows[1].failed);
  EXPECT_FALSE(rows[2].failed);
  EXPECT_TRUE(rows[3].failed);
}

TEST(EvalTable, CsvReadsBackWhatWasWritten) {
  auto rows = sampleRows();
  markFailures(rows, FailureThresholds{});
  const std::string path = tempPath("eval.csv");
  writeEvalCsv(path, rows);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  const auto back = readEvalCsv(path);
  ASSERT_EQ(back.size(), rows.size());
  auto same = [](double a, double b) {  // written with 10 significant digits
    return (std::isnan(a) && std::isnan(b)) || a == b || std::abs(a - b) <= 1e-9 * std::abs(a);
  };
  for (std::size_t i = 0; i < rows.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(back[i].source, rows[i].source);
    EXPECT_EQ(back[i].seed, rows[i].seed);
    EXPECT_EQ(back[i].method, rows[i].method);
    EXPECT_EQ(back[i].status, rows[i].status);
    EXPECT_EQ(back[i].failed, rows[i].failed);
    EXPECT_EQ(back[i].failure, rows[i].failure);
    EXPECT_EQ(back[i].warnings, rows[i].warnings);
    EXPECT_EQ(back[i].wrong_calibration, rows[i].wrong_calibration);
    EXPECT_TRUE(same(back[i].rest_duration, rows[i].rest_duration));
    EXPECT_EQ(back[i].block, rows[i].block);
    EXPECT_EQ(back[i].window_samples, rows[i].window_samples);
    EXPECT_EQ(back[i].rest_samples, rows[i].rest_samples);
    for (auto f : {&SensorNoise::declared, &SensorNoise::truth, &SensorNoise::reported,
                   &SensorNoise::reported_rel_sigma})
      for (auto n : {&EvalRow::noise_gyro, &EvalRow::noise_accel, &EvalRow::noise_doppler})
        EXPECT_TRUE(same(back[i].*n.*f, rows[i].*n.*f));
    for (auto f : {&EvalRow::imu_noise_factor, &EvalRow::doppler_noise_factor,
                   &EvalRow::time_offset_true, &EvalRow::time_offset_reported,
                   &EvalRow::time_offset_reported_sigma, &EvalRow::crb_gyro_bias_zero_rate})
      EXPECT_TRUE(same(back[i].*f, rows[i].*f)) << back[i].*f << " vs " << rows[i].*f;
    for (auto f : {&EvalRow::speed,           &EvalRow::velocity_err,
                   &EvalRow::gravity_err_deg, &EvalRow::gravity_bound_deg,
                   &EvalRow::gyro_bias_err,   &EvalRow::accel_bias_err,
                   &EvalRow::position_err,    &EvalRow::time_ms,
                   &EvalRow::crb_velocity,    &EvalRow::crb_gravity_deg,
                   &EvalRow::crb_gyro_bias,   &EvalRow::crb_accel_bias,
                   &EvalRow::nees_velocity,   &EvalRow::nees_tilt,
                   &EvalRow::nees_gyro_bias,  &EvalRow::nees_accel_bias,
                   &EvalRow::sigma_velocity,  &EvalRow::sigma_gravity_deg,
                   &EvalRow::sigma_gyro_bias, &EvalRow::sigma_accel_bias})
      EXPECT_TRUE(same(back[i].*f, rows[i].*f)) << back[i].*f << " vs " << rows[i].*f;
  }
  std::filesystem::remove(path);
}

TEST(EvalTable, BadCsvNamesFileAndLine) {
  const std::string path = tempPath("bad.csv");
  // The sample rows (lines 1-5) and one bad line: the error names the file, line 6 and `what`.
  auto expectError = [&](const std::string& bad_line, const std::string& what) {
    writeEvalCsv(path, sampleRows());
    std::ofstream(path, std::ios::app) << bad_line << "\n";
    try {
      readEvalCsv(path);
      ADD_FAILURE() << "accepted: " << bad_line;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path + ": line 6: " + what), std::string::npos)
          << e.what();
    }
  };
  // A row of the 56 columns: source, seed, method, status, 24 numbers, confident_wrong, failed,
  // failure, warnings, wrong_calibration, rest_s, block, 18 numbers, window_samples, rest_samples
  // and the zero-rate ratio.
  auto line = [](const std::string& seed, const std::string& first_number,
                 const std::string& tail = "0,0,0", const std::string& samples = "100,50,") {
    std::string l = "dyna_02," + seed + ",free-init,ok," + first_number;
    for (int i = 0; i < 23; ++i) l += ",";
    l += ",,0,," + tail + ",imu×2";
    for (int i = 0; i < 18; ++i) l += ",";
    return l + "," + samples;
  };
  expectError(line("1", "abc"), "not a number");
  expectError(line("2.7", ""), "seed");  // was truncated to 2
  expectError(line("3", "", "1.5,0,0"), "warnings is not a whole number");
  expectError(line("4", "", "0,yes,0"), "wrong_calibration must be 0 or 1");
  expectError(line("5", "", "0,0,x"), "not a number");
  expectError(line("6", "", "0,0,0", "100,-1,"), "rest_samples is not a whole number");
  expectError(line("7", "", "0,0,0", "100.5,50,"), "window_samples is not a whole number");
  expectError(line("8", "", "0,0,0", "100,50,abc"), "not a number");
  expectError("dyna_02,1,free-init,ok,,,,,,,,,0,", "14 fields, expected 56");
  std::filesystem::remove(path);
  EXPECT_THROW(readEvalCsv(path), std::runtime_error);  // missing file
}

TEST(EvalTable, SummaryHasThePaperLayoutAndMarksFailures) {
  auto rows = sampleRows();
  markFailures(rows, FailureThresholds{});
  const std::string md = markdownSummary(rows, FailureThresholds{});
  // Inputs are columns; one row per method in each metric block.
  EXPECT_NE(md.find("| metric | method | dyna_01 | a dir, with \"quotes\"/x.rawlog |"),
            std::string::npos)
      << md;
  // The worst of the two free-init seeds, marked: 1 of 2 over the gravity threshold.
  EXPECT_NE(md.find("| gravity err [deg] | free-init | 3.50 ×1/2 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| velocity err [m/s] | fast-lio2 | 1.22 × |"), std::string::npos) << md;
  // No state at all: a cross alone.
  EXPECT_NE(md.find("| velocity err [m/s] | dlio |  | × |"), std::string::npos) << md;
  EXPECT_NE(md.find("| failed runs | free-init | 1/2 |"), std::string::npos) << md;
}

TEST(EvalSummary, QuantilesInterpolateBetweenOrderStatistics) {
  EXPECT_DOUBLE_EQ(quantile({3, 1, 2}, 0.5), 2);
  EXPECT_DOUBLE_EQ(quantile({4, 1, 3, 2}, 0.5), 2.5);
  EXPECT_DOUBLE_EQ(quantile({0, 10}, 0.95), 9.5);
  EXPECT_DOUBLE_EQ(quantile({7}, 0.95), 7);
  EXPECT_TRUE(std::isnan(quantile({}, 0.5)));
}

/// n ok runs of one method with err/bound = 1..n on every quantity, NEES 1..n.
std::vector<EvalRow> ratioRows(int n) {
  std::vector<EvalRow> rows;
  for (int i = 1; i <= n; ++i) {
    EvalRow r;
    r.source = "p" + std::to_string(i % 3);
    r.seed = i;
    r.method = "m";
    r.velocity_err = 0.001 * i;
    r.crb_velocity = 0.001;
    r.gravity_err_deg = 0.1 * i;
    r.crb_gravity_deg = 0.1;
    r.gyro_bias_err = 0.0005 * i;
    r.crb_gyro_bias = 0.0005;
    r.accel_bias_err = 0.02 * i;
    r.crb_accel_bias = 0.02;
    r.nees_velocity = r.nees_tilt = r.nees_gyro_bias = r.nees_accel_bias = i;
    // Own sigmas at 0.9 of the bound for runs 1..5 (below 0.95 of it), at the bound after.
    const double own = i <= 5 ? 0.9 : 1.0;
    r.sigma_velocity = own * r.crb_velocity;
    r.sigma_gravity_deg = own * r.crb_gravity_deg;
    r.sigma_gyro_bias = own * r.crb_gyro_bias;
    r.sigma_accel_bias = own * r.crb_accel_bias;
    r.rest_duration = 0;
    rows.push_back(r);
  }
  return rows;
}

TEST(EvalSummary, CountsStatusesRatiosNeesAndConfidentWrongAnswers) {
  std::vector<EvalRow> rows = ratioRows(20);
  EvalRow failed;
  failed.method = "m";
  failed.status = "ambiguous_motion";
  rows.push_back(failed);
  failed.status = "something_new";
  rows.push_back(failed);
  const std::vector<EvalRow> all = rows;
  const auto s = summarize(rows);
  ASSERT_EQ(s.size(), 1u);
  const MethodSummary& m = s[0];
  EXPECT_EQ(m.runs, 22);
  const auto& names = statusNames();
  ASSERT_EQ(names.size(), 7u);
  EXPECT_EQ(m.status_counts[0], 20);  // ok
  EXPECT_EQ(m.status_counts[5], 1);   // ambiguous_motion
  EXPECT_EQ(m.status_counts[7], 1);   // any other status
  EXPECT_EQ(m.with_bound, 20);
  for (int q = 0; q < 4; ++q) {
    EXPECT_NEAR(m.ratio_median[q], 10.5, 1e-9);
    EXPECT_NEAR(m.ratio_p95[q], 19.05, 1e-9);
  }
  // NEES 1..20: above 16.27 (3 dof): 17..20; above 13.82 (2 dof): 14..20.
  EXPECT_EQ(m.nees_above[0], 4);
  EXPECT_EQ(m.nees_above[1], 7);
  EXPECT_EQ(m.with_nees, 20);
  EXPECT_EQ(m.with_sigma, 20);
  for (int q = 0; q < 4; ++q) EXPECT_EQ(m.sigma_below_bound[q], 5);
  // More than 3x on some quantity and above its floor (0.02 m/s, 0.2 deg, 0.001 rad/s,
  // 0.03 m/s^2): gravity from ratio 4 on (0.4 deg), so runs 4..20.
  EXPECT_EQ(m.confident_wrong, 17);
  EXPECT_EQ(rows[2].confidentlyWrong(), "");  // ratio 3: not more than 3x
  EXPECT_EQ(rows[3].confidentlyWrong(), "gravity,b_g,b_a");
  EXPECT_EQ(rows[19].confidentlyWrong(), "gravity,b_g,b_a");  // velocity 0.02: not above
  rows[19].velocity_err = 0.021;
  EXPECT_EQ(rows[19].confidentlyWrong(), "velocity,gravity,b_g,b_a");
  rows[19].status = "inconsistent_data";  // no state: never a confident wrong answer
  EXPECT_EQ(rows[19].confidentlyWrong(), "");

  const std::string md = boundsMarkdown(ratioRows(20));
  EXPECT_NE(md.find("| m | 20 / 20 | 10.5 | 19.1 | 10.5 | 19.1 | 10.5 | 19.1 | 10.5 | 19.1 | 17 |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| m | 4/20 (20.0 %) | 7/20 (35.0 %) | 4/20 (20.0 %) | 4/20 (20.0 %) |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| m | 5/20 (25.0 %) | 5/20 (25.0 %) | 5/20 (25.0 %) | 5/20 (25.0 %) |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| m | 20 | 0 | 0 | 0 | 0 | 0 | 0 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| p1 | 4 | m | gravity,b_g,b_a | 4.00, 4.00, 4.00, 4.00 |"), std::string::npos)
      << md;

  // A capped list counts the rest.
  const std::string capped = boundsMarkdown(ratioRows(20), {}, 2);
  EXPECT_NE(capped.find("| p1 | 4 | m |"), std::string::npos) << capped;
  EXPECT_EQ(capped.find("| p0 | 6 | m |"), std::string::npos) << capped;
  EXPECT_NE(capped.find("| … | | m | 15 more | |"), std::string::npos) << capped;

  const std::string path = tempPath("summary.csv");
  writeSummaryCsv(path, all);
  std::ifstream f(path);
  std::string header, line;
  std::getline(f, header);
  std::getline(f, line);
  EXPECT_EQ(header.rfind("method,block,runs,ok,not_enough_data,", 0), 0u) << header;
  EXPECT_EQ(line.rfind("m,,22,20,0,0,0,0,1,0,1,20,10.5,19.05,", 0), 0u) << line;
  std::filesystem::remove(path);
}

// Runs handed different misdeclarations are summarized apart, one row per method and block, the
// blocks in the order of their numbers; within each: the static starts against the zero-rate
// bound and the noise the method reports against the truth.
TEST(EvalSummary, BlocksOfFactorsStaticStartsAndReportedNoise) {
  std::vector<EvalRow> rows;
  for (const char* block : {"imu×4", "imu×0.25", "imu×1", "imu×16"})
    for (EvalRow r : ratioRows(4)) {
      r.block = block;
      rows.push_back(r);
    }
  // In block imu×4: three static starts (whole window at rest), b_g 1, 2 and 4 times the
  // zero-rate bound; one run only partly at rest (not a static start).
  for (int i = 0; i < 4; ++i) {
    EvalRow& r = rows[static_cast<std::size_t>(i)];
    r.window_samples = 100;
    r.rest_samples = i < 3 ? 100 : 60;
    r.crb_gyro_bias_zero_rate = r.gyro_bias_err / (i == 0 ? 1 : 2 * i);
  }
  // Reported noise in block imu×1: the gyro within 20 % (resolved), 30 % off (resolved), within
  // 20 % but not resolved (relative sigma 10 %), and one without a report.
  const double reported[4] = {0.0023, 0.0026, 0.0021, kNoValue};
  const double rel_sigma[4] = {0.05, 0.05, 0.10, kNoValue};
  for (int i = 0; i < 4; ++i) {
    EvalRow& r = rows[static_cast<std::size_t>(8 + i)];
    r.noise_gyro = {0.002, 0.002, reported[i], rel_sigma[i]};
    r.time_offset_true = 0.008;
    r.time_offset_reported = 0.008 + 0.001 * i;
    r.time_offset_reported_sigma = 0.001;  // within 3 sigma: i = 0..3
  }
  const auto s = summarize(rows);
  ASSERT_EQ(s.size(), 4u);
  EXPECT_EQ(s[0].block, "imu×0.25");
  EXPECT_EQ(s[1].block, "imu×1");
  EXPECT_EQ(s[2].block, "imu×4");
  EXPECT_EQ(s[3].block, "imu×16");
  EXPECT_EQ(s[2].label(), "m · imu×4");
  for (const MethodSummary& m : s) {
    EXPECT_EQ(m.runs, 4);
    EXPECT_NEAR(m.ratio_median[0], 2.5, 1e-12);
  }
  EXPECT_EQ(s[2].static_starts, 3);
  EXPECT_EQ(s[2].static_gyro_bias_above_zero_rate, 1);
  EXPECT_NEAR(s[2].zero_rate_ratio_median, 2.0, 1e-12);
  EXPECT_EQ(s[0].static_starts, 0);
  EXPECT_TRUE(std::isnan(s[0].zero_rate_ratio_median));
  EXPECT_EQ(s[1].noise_resolved[0], 2);
  EXPECT_EQ(s[1].noise_within[0], 1);
  EXPECT_EQ(s[1].noise_resolved[1], 0);
  EXPECT_EQ(s[1].time_offset_reported, 4);
  EXPECT_EQ(s[1].time_offset_within, 4);
  const std::string md = boundsMarkdown(rows);
  EXPECT_NE(md.find("| m · imu×0.25 | 4 / 4 |"), std::string::npos) << md;
  EXPECT_LT(md.find("| m · imu×1 | 4 / 4 |"), md.find("| m · imu×16 | 4 / 4 |")) << md;
  EXPECT_NE(md.find("| m · imu×4 | 1/3 | 2.00 | 3.80 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| m · imu×0.25 | – | – | – |"), std::string::npos) << md;
  EXPECT_NE(md.find("| m · imu×1 | 1/2 (50.0 %) | – | – | 4/4 (100.0 %) |"), std::string::npos)
      << md;
  // Without any report: one sentence instead of the table.
  const std::string plain = boundsMarkdown(ratioRows(3));
  EXPECT_NE(plain.find("No method reports the noise or the clock offset it used"),
            std::string::npos);
  EXPECT_NE(plain.find("| m | – | – | – |"), std::string::npos) << plain;
}

// A run handed a wrong calibration is a test of the verdict, not of the estimator against its
// bound: it stays out of the ratios, the NEES and the confident-wrong count, and is counted
// apart as flagged (a warning came with the wrong state) or plain wrong.
TEST(EvalSummary, WrongCalibrationRunsAreCountedApart) {
  std::vector<EvalRow> rows = ratioRows(2);  // ratios 1 and 2: neither confidently wrong
  EvalRow bad = ratioRows(10).back();        // ratio 10 on every quantity
  bad.wrong_calibration = true;
  rows.push_back(bad);  // wrong, no warning
  bad.warnings = 1;
  rows.push_back(bad);  // wrong, flagged
  bad.status = "inconsistent_data";
  rows.push_back(bad);  // no state
  const auto s = summarize(rows);
  ASSERT_EQ(s.size(), 1u);
  const MethodSummary& m = s[0];
  EXPECT_EQ(m.runs, 5);
  EXPECT_EQ(m.with_bound, 2);
  EXPECT_EQ(m.with_nees, 2);
  EXPECT_EQ(m.confident_wrong, 0);
  EXPECT_NEAR(m.ratio_median[0], 1.5, 1e-9);
  EXPECT_EQ(m.wrong_calibration_runs, 3);
  EXPECT_EQ(m.wrong_calibration_ok, 2);
  EXPECT_EQ(m.wrong_calibration_flagged, 1);
  EXPECT_EQ(m.wrong_calibration_plain_wrong, 1);
  const std::string md = boundsMarkdown(rows);
  EXPECT_NE(md.find("| m | 3 | 2 | 1 | 1 |"), std::string::npos) << md;
}

TEST(DisplacementError, IsFreeOfTheWorldFrame) {
  // The truth moves 2 m along its body x axis, yawed 30 deg in its world; the estimate's world
  // has the start yaw at zero. Same body-frame displacement: zero error.
  const Quat q_true(Exp(Vec3(0, 0, 30.0 * M_PI / 180.0)));
  eval::StateTruth start, end;
  start.q_wb = end.q_wb = q_true;
  start.p_w = Vec3(5, 6, 7);
  end.p_w = Vec3(5, 6, 7) + q_true * Vec3(2, 0, 0);
  InitResult r;
  r.state.status = InitStatus::Ok;
  r.trajectory.push_back(PoseSample{});
  r.state.p_w = Vec3(2, 0, 0);
  EXPECT_NEAR(eval::displacementError(r, start, end), 0.0, 1e-12);
  r.state.p_w = Vec3(2, 0.3, -0.4);
  EXPECT_NEAR(eval::displacementError(r, start, end), 0.5, 1e-12);
  r.state.status = InitStatus::NotEnoughData;
  EXPECT_TRUE(std::isnan(eval::displacementError(r, start, end)));
}

TEST(MakeEvalRow, ErrorsAgainstTheTruthAtTheStateTime) {
  // The truth is yawed 30 deg and tilted in its world; the estimate's world differs by a yaw
  // (gauge-free errors must not see it). Errors put in by hand on top of the truth.
  const Mat3 R_true = Exp(Vec3(0.1, 0, 30.0 * M_PI / 180.0));
  auto truth = [&](double t) {
    eval::StateTruth gt;
    gt.q_wb = Quat(R_true);
    gt.p_w = Vec3(5, 6, 7) + t * (R_true * Vec3(2, 0, 0));
    gt.v_w = R_true * Vec3(2, 0, 0);
    gt.b_g = Vec3(0.01, 0, 0);
    gt.b_a = R_true.transpose() * Vec3(0.3, 0.4, 0.1);  // horizontal 0.5 m/s^2 in w
    return gt;
  };
  const Quat q_gauge(Eigen::AngleAxisd(0.7, Vec3::UnitZ()));
  MethodRun m;
  m.method = "free-init";
  m.time_ms = 12;
  InitialState& s = m.result.state;
  s.status = InitStatus::Ok;
  s.timestamp = 2;
  s.q_wb = q_gauge * Quat(R_true);
  s.v_w = q_gauge * (R_true * Vec3(2, 0.3, -0.4));  // 0.5 m/s off in b
  s.g_w = q_gauge * Vec3(0, 0, -kGravity);
  s.b_g = truth(2).b_g + Vec3(0, 0.002, 0);
  s.b_a = truth(2).b_a + Vec3(0, 0, 0.05);
  s.p_w = q_gauge * (R_true * Vec3(4, 0, 0));  // 2 s at 2 m/s along body x
  PoseSample p0;
  p0.t = 0;
  p0.q_wb = s.q_wb;
  m.result.trajectory.push_back(p0);
  const EvalRow row = makeEvalRow("dyna_01", 3, m, truth);
  EXPECT_EQ(row.source, "dyna_01");
  EXPECT_EQ(row.seed, 3);
  EXPECT_EQ(row.method, "free-init");
  EXPECT_EQ(row.status, "ok");
  EXPECT_EQ(row.time_ms, 12);
  EXPECT_NEAR(row.speed, 2, 1e-12);
  EXPECT_NEAR(row.velocity_err, 0.5, 1e-12);
  EXPECT_NEAR(row.gravity_err_deg, 0, 1e-6);
  EXPECT_NEAR(row.gravity_bound_deg,
              std::atan2(0.5, kGravity) * 180 / M_PI + kGravityBoundMarginDeg, 1e-9);
  EXPECT_NEAR(row.gyro_bias_err, 0.002, 1e-12);
  EXPECT_NEAR(row.accel_bias_err, 0.05, 1e-12);
  EXPECT_NEAR(row.position_err, 0, 1e-9);
  EXPECT_TRUE(std::isnan(row.crb_velocity));  // no bound given
  EXPECT_GE(row.nees_velocity, 0);
  // With a bound: its sqrt-traces, and the ratios.
  eval::Bound b;
  b.ok = true;
  b.velocity = 0.25;
  b.gravity_deg = 0.1;
  b.gyro_bias = 0.001;
  b.accel_bias = 0.01;
  const EvalRow bounded = makeEvalRow("dyna_01", 3, m, truth, &b);
  EXPECT_DOUBLE_EQ(bounded.crb_velocity, 0.25);
  EXPECT_NEAR(bounded.ratioVelocity(), 2.0, 1e-12);
  EXPECT_NEAR(bounded.ratioGyroBias(), 2.0, 1e-9);
  EXPECT_NEAR(bounded.ratioAccelBias(), 5.0, 1e-9);
  EXPECT_EQ(bounded.confidentlyWrong(), "b_a");  // velocity 2x, gravity 0, b_g 2x
  // No state: status only, every error NaN, the truth not asked.
  s.status = InitStatus::NotEnoughData;
  const EvalRow none = makeEvalRow(
      "x", 0, m, [](double) -> eval::StateTruth { throw std::runtime_error("truth asked"); });
  EXPECT_EQ(none.status, toString(InitStatus::NotEnoughData));
  EXPECT_TRUE(std::isnan(none.velocity_err));
  EXPECT_TRUE(std::isnan(none.gravity_bound_deg));
  EXPECT_TRUE(std::isnan(none.position_err));
}

TEST(ParallelFor, RunsEveryJobOnceAndReportsTheLowestFailure) {
  for (unsigned threads : {1u, 2u, 5u}) {
    std::vector<std::atomic<int>> hits(37);
    parallelFor(hits.size(), threads, [&](std::size_t i) { ++hits[i]; });
    for (const auto& h : hits) EXPECT_EQ(h.load(), 1);
    try {
      parallelFor(20, threads, [](std::size_t i) {
        if (i == 7 || i == 13) throw std::runtime_error("job " + std::to_string(i));
      });
      FAIL() << "no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "job 7");
    }
  }
}

/// In a child process: address space for one more thread stack only, then parallelFor with 4
/// threads. The second thread cannot start; the first must be joined before the error is rethrown
/// (a joinable std::thread destroyed in the unwinding would call std::terminate: SIGABRT).
void parallelForWhenAThreadCannotStart() {
  pthread_attr_t attr;
  std::size_t stack = 0;
  if (pthread_getattr_default_np(&attr) != 0 || pthread_attr_getstacksize(&attr, &stack) != 0)
    std::_Exit(2);
  long pages = 0;
  if (!(std::ifstream("/proc/self/statm") >> pages)) std::_Exit(3);
  const auto used = static_cast<rlim_t>(pages) * static_cast<rlim_t>(sysconf(_SC_PAGESIZE));
  const rlimit limit{used + stack + stack / 2, RLIM_INFINITY};
  if (setrlimit(RLIMIT_AS, &limit) != 0) std::_Exit(4);
  try {
    parallelFor(1000, 4, [](std::size_t) {});
  } catch (const std::system_error&) {
    std::_Exit(0);
  }
  std::_Exit(6);  // every thread started: the limit did not bite
}

TEST(ParallelFor, JoinsTheStartedThreadsWhenAThreadCannotStart) {
  // "threadsafe": the child is a fresh run of this test alone, without the thread stacks that
  // glibc caches from earlier tests (a cached stack needs no new address space).
  ::testing::FLAGS_gtest_death_test_style = "threadsafe";
  EXPECT_EXIT(parallelForWhenAThreadCannotStart(), ::testing::ExitedWithCode(0), "");
}

TEST(Plot, WritesAReadablePngWithTheData) {
  Plot p;
  p.title = "test";
  p.x_label = "t [s]";
  p.y_label = "error [m/s]";
  p.log_y = true;
  Series s;
  s.label = "line";
  s.color = plot::Rgb{255, 0, 0};  // pure red, not used by the axes or text
  s.x = {0, 1, 2};
  s.y = {0.01, 0.1, 1};
  p.add(s);
  const std::string path = tempPath("plot.png");
  savePng(path, tile({p.render(320, 240), p.render(320, 240)}, 2));
  const cv::Mat img = cv::imread(path);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, 640);
  EXPECT_EQ(img.rows, 240);
  int red = 0;
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x) {
      const auto& px = img.at<cv::Vec3b>(y, x);
      if (px[2] > 200 && px[1] < 60 && px[0] < 60) ++red;
    }
  EXPECT_GT(red, 200);  // two panels of a line across the plot area
  std::filesystem::remove(path);
}

/// A font of 7 x 11 px boxes that draws nothing and keeps what it was asked to draw.
class RecordingFont : public PanelFont {
 public:
  struct Text {
    std::string text;
    cv::Point top_left;
    Role role;
  };
  cv::Size size(const std::string& text, Role) const override {
    return {7 * static_cast<int>(text.size()), 11};
  }
  void draw(cv::Mat&, const std::string& text, cv::Point top_left, Role role,
            const plot::Rgb&) const override {
    drawn.push_back({text, top_left, role});
  }
  const Text* find(const std::string& text) const {
    for (const Text& t : drawn)
      if (t.text == text) return &t;
    return nullptr;
  }
  mutable std::vector<Text> drawn;
};

/// A stacked panel of one rising line over x in [0, 1] s.
plot::PanelSpec stackedPanel() {
  plot::PanelSpec spec;
  spec.title = "v_b.x [m/s]";
  spec.x.min = 0;
  spec.x.max = 1;
  spec.x.unit = " s";
  spec.y.min = 0;
  spec.y.max = 1;
  Series s;
  s.x = {0, 1};
  s.y = {0, 1};
  spec.series = {s};
  return spec;
}

TEST(Plot, EveryTextOfAPanelIsDrawnInItsFont) {
  const plot::Box cell{0.1, 0.1, 0.9, 0.5};
  const auto width = [](const std::string& t) { return 7.0 * static_cast<double>(t.size()) / 640; };
  cv::Mat img(400, 640, CV_8UC3, cv::Scalar(255, 255, 255));
  plot::PanelSpec spec = stackedPanel();
  const plot::PanelLayout l = plot::layoutPanel(spec, cell, plot::stackedPanelStyle(), width);
  RecordingFont font;
  drawPanel(img, spec, cell, plot::stackedPanelStyle(), font);
  // The title at the layout's top-left corner inside the area; each tick label 8 px under the
  // area (centred on its tick) or 6 px left of it (centred on its height).
  const RecordingFont::Text* title = font.find("v_b.x [m/s]");
  ASSERT_NE(title, nullptr);
  EXPECT_EQ(title->role, PanelFont::Role::Title);
  EXPECT_EQ(title->top_left, cv::Point(static_cast<int>(std::lround(l.title_x * 640)),
                                       static_cast<int>(std::lround(l.title_y * 400))));
  const int area_x0 = static_cast<int>(std::lround(l.area.x0 * 640));
  const int area_y1 = static_cast<int>(std::lround(l.area.y1 * 400));
  ASSERT_EQ(l.x.labels.front(), "0.0 s");
  const RecordingFont::Text* x0 = font.find("0.0 s");
  ASSERT_NE(x0, nullptr);
  EXPECT_EQ(x0->top_left, cv::Point(area_x0 - 7 * 5 / 2, area_y1 + 8));
  ASSERT_EQ(l.y.labels.front(), "0.0");
  const RecordingFont::Text* y0 = font.find("0.0");
  ASSERT_NE(y0, nullptr);
  EXPECT_EQ(y0->top_left, cv::Point(area_x0 - 7 * 3 - 6, area_y1 - 11 / 2));
  EXPECT_EQ(font.drawn.size(), 1 + l.x.labels.size() + l.y.labels.size());

  // Without tick labels on x (a panel over a shared time axis) only the title and y are drawn.
  spec.x.tick_labels = false;
  RecordingFont bare;
  drawPanel(img, spec, cell, plot::stackedPanelStyle(), bare);
  EXPECT_EQ(bare.find("0.0 s"), nullptr);
  EXPECT_EQ(bare.drawn.size(), 1 + l.y.labels.size());
}

TEST(Plot, ATitleInsideTheAreaStaysOnItsWhiteBoxOverTheData) {
  // A line 40 px wide along the top of the area runs under the title's corner.
  const plot::Box cell{0, 0, 1, 1};
  plot::PanelSpec spec = stackedPanel();
  spec.series[0].y = {1, 1};
  spec.series[0].thickness = 40;
  spec.series[0].color = plot::Rgb{255, 0, 0};
  cv::Mat img(200, 640, CV_8UC3, cv::Scalar(255, 255, 255));
  RecordingFont font;
  drawPanel(img, spec, cell, plot::stackedPanelStyle(), font);
  const RecordingFont::Text* title = font.find("v_b.x [m/s]");
  ASSERT_NE(title, nullptr);
  // Left of the text and under it: the box; right of the box: the line.
  EXPECT_EQ(img.at<cv::Vec3b>(title->top_left + cv::Point(-3, 5)), cv::Vec3b(255, 255, 255));
  EXPECT_EQ(img.at<cv::Vec3b>(title->top_left + cv::Point(40, 11)), cv::Vec3b(255, 255, 255));
  EXPECT_EQ(img.at<cv::Vec3b>(title->top_left + cv::Point(7 * 11 + 10, 5)), cv::Vec3b(0, 0, 255));
}

// The methods in the order of the tables, each with its kind of velocity track.
TEST(RunMethods, EveryMethodInTableOrderWithItsTrack) {
  sim::ScenarioConfig sc = sim::preset("stat_01", 1);
  sc.duration = 1.0;
  sc.points_per_frame = 2000;
  const sim::Recording rec = sim::simulate(sc);
  MethodOptions options;
  options.dlio_duration = 0.8;
  const auto runs =
      runMethods(FreeInitConfig{}, rec.imu, rec.frames, rec.declared_extrinsics, options);
  ASSERT_EQ(runs.size(), 4u);
  const char* const names[] = {"free-init", "fast-lio2", "dlio", "doppler-ls"};
  for (std::size_t i = 0; i < runs.size(); ++i) {
    SCOPED_TRACE(names[i]);
    EXPECT_EQ(runs[i].method, names[i]);
    ASSERT_TRUE(runs[i].result.state.ok()) << runs[i].result.state.message;
    EXPECT_FALSE(runs[i].track.empty());
    EXPECT_EQ(runs[i].track_per_frame, i == 3);
  }
  EXPECT_EQ(runs[0].track.size(), runs[0].result.velocities.size());
  for (const std::size_t i :
       {std::size_t{1}, std::size_t{2}}) {  // the static means: v = 0 over their window
    EXPECT_EQ(runs[i].track.size(), runs[i].result.trajectory.size());
    for (const TimedVelocity& v : runs[i].track) EXPECT_EQ(v.v_b, Vec3::Zero());
  }
  options.baselines = false;
  const auto alone =
      runMethods(FreeInitConfig{}, rec.imu, rec.frames, rec.declared_extrinsics, options);
  ASSERT_EQ(alone.size(), 1u);
  EXPECT_EQ(alone[0].method, "free-init");
}

using apps::EvalApp;
using apps::EvalAppParams;

EvalApp::Action parseLine(EvalApp& app, std::vector<const char*> args) {
  args.insert(args.begin(), "freeinit-eval");
  return app.parse(static_cast<int>(args.size()), args.data());
}

TEST(EvalApp, ParsesTheCommandLine) {
  EvalApp app;
  EXPECT_EQ(parseLine(app, {"-q", "--seeds", "2", "--no-baselines", "--dlio-duration", "0.8",
                            "--csv", "out/e.csv", "dyna_04", "stat_01"}),
            EvalApp::Action::Run);
  const EvalAppParams& p = app.params;
  EXPECT_TRUE(p.quiet);
  EXPECT_EQ(p.seeds, 2);
  EXPECT_FALSE(p.methods.baselines);
  EXPECT_EQ(p.methods.dlio_duration, 0.8);
  EXPECT_EQ(p.csv, "out/e.csv");
  EXPECT_EQ(p.presets, (std::vector<std::string>{"dyna_04", "stat_01"}));
  EXPECT_EQ(p.command,
            "freeinit-eval -q --seeds 2 --no-baselines --dlio-duration 0.8 --csv out/e.csv "
            "dyna_04 stat_01");
  EXPECT_EQ(parseLine(app, {}), EvalApp::Action::Run);  // the defaults again
  EXPECT_EQ(app.params.seeds, 3);
  EXPECT_TRUE(app.params.presets.empty());  // every preset
  EXPECT_FALSE(app.params.imu_noise_factor || app.params.doppler_noise_factor ||
               app.params.time_offset);
  // What the estimator is handed: a value or a range.
  ASSERT_EQ(parseLine(app, {"--imu-noise-factor", "0.25:4", "--doppler-noise-factor", "2",
                            "--time-offset", "0.008"}),
            EvalApp::Action::Run);
  ASSERT_TRUE(app.params.imu_noise_factor && app.params.doppler_noise_factor &&
              app.params.time_offset);
  EXPECT_EQ(app.params.imu_noise_factor->lo, 0.25);
  EXPECT_EQ(app.params.imu_noise_factor->hi, 4.0);
  EXPECT_EQ(app.params.doppler_noise_factor->lo, 2.0);
  EXPECT_EQ(app.params.doppler_noise_factor->hi, 2.0);
  EXPECT_EQ(app.params.time_offset->lo, 0.008);
  EXPECT_EQ(app.params.time_offset->hi, 0.008);
}

/// recordingDigest of a case's scenario, shortened to keep the simulation small.
std::uint64_t digestOf(const apps::EvalCase& c) {
  sim::ScenarioConfig sc = c.scenario;
  sc.duration = 0.25;
  sc.points_per_frame = std::min(sc.points_per_frame, 1500);
  return sim::test::recordingDigest(sim::simulate(sc));
}

// A seed's recording is the same whatever the noise factors (they only change what the estimator
// is handed), so runs at different factors are paired; the injected offset changes the LiDAR
// stamps alone, and the runs that carry it are measured against their bound.
TEST(EvalApp, RunsArePairedAcrossFactors) {
  auto casesOf = [](std::vector<const char*> args) {
    EvalApp app;
    for (const char* a : {"--random", "3", "--seed-base", "44100001", "--no-baselines"})
      args.push_back(a);
    parseLine(app, args);
    return app.cases();
  };
  const auto plain = casesOf({});
  const auto quarter = casesOf({"--imu-noise-factor", "0.25", "--doppler-noise-factor", "4"});
  const auto drawn = casesOf({"--imu-noise-factor", "0.25:4", "--doppler-noise-factor", "0.25:4"});
  const auto offset = casesOf({"--time-offset", "0.008"});
  ASSERT_EQ(plain.size(), 3u);
  for (std::size_t i = 0; i < plain.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(plain[i].block, "");
    EXPECT_EQ(plain[i].misdeclared.imu_noise_factor, 1.0);
    EXPECT_EQ(quarter[i].block, "imu×0.25 doppler×4");
    EXPECT_EQ(quarter[i].misdeclared.imu_noise_factor, 0.25);
    EXPECT_EQ(quarter[i].misdeclared.doppler_noise_factor, 4.0);
    EXPECT_GE(drawn[i].misdeclared.imu_noise_factor, 0.25);
    EXPECT_LE(drawn[i].misdeclared.imu_noise_factor, 4.0);
    EXPECT_EQ(drawn[i].block.rfind("imu≈×", 0), 0u) << drawn[i].block;
    EXPECT_EQ(std::abs(offset[i].scenario.lidar_time_offset), 0.008);
    EXPECT_EQ(offset[i].scenario.lidar_time_offset, offset[i].misdeclared.time_offset);
    EXPECT_EQ(offset[i].block, "offset±8ms");
    EXPECT_EQ(quarter[i].seed, plain[i].seed);
    const std::uint64_t digest = digestOf(plain[i]);
    EXPECT_EQ(digestOf(quarter[i]), digest);
    EXPECT_EQ(digestOf(drawn[i]), digest);
    apps::EvalCase back = offset[i];
    EXPECT_NE(digestOf(back), digest);
    back.scenario.lidar_time_offset = plain[i].scenario.lidar_time_offset;
    EXPECT_EQ(digestOf(back), digest);  // the offset is all it changes
    // An injected offset is measured against the bound; a drawn extrinsics error stays apart.
    const bool extrinsics_wrong = plain[i].scenario.declared_rotation_error_deg.norm() > 0 ||
                                  plain[i].scenario.declared_position_error.norm() > 0;
    EXPECT_EQ(offset[i].wrong_calibration, extrinsics_wrong);
    EXPECT_EQ(quarter[i].wrong_calibration, plain[i].wrong_calibration);
  }
  // Drawn per run: not all the same.
  EXPECT_NE(drawn[0].misdeclared.imu_noise_factor, drawn[1].misdeclared.imu_noise_factor);
}

TEST(EvalApp, HelpAndVersionWinWhateverElseIsOnTheLine) {
  EvalApp app;
  EXPECT_EQ(parseLine(app, {"--seeds", "2.7", "--help", "--csv", "x.csv"}), EvalApp::Action::Help);
  EXPECT_EQ(parseLine(app, {"--bogus", "-h"}), EvalApp::Action::Help);
  EXPECT_EQ(parseLine(app, {"--bogus", "--version", "--help"}), EvalApp::Action::Version);
  EXPECT_EQ(std::string(EvalApp::usage()).rfind("Usage: freeinit-eval", 0), 0u);
}

// The exit codes of the command line (its output is the shell tests' in tests/CMakeLists.txt).
TEST(EvalApp, MainReturnsTheExitCode) {
  auto exitCode = [](std::vector<const char*> args) {
    args.insert(args.begin(), "freeinit-eval");
    return EvalApp::main(static_cast<int>(args.size()), args.data());
  };
  EXPECT_EQ(exitCode({"--bogus", "--version"}), 0);
  EXPECT_EQ(exitCode({"--seeds", "2.7"}), 2);
  EXPECT_EQ(exitCode({"-q", "--duration", "0"}), 2);
  const std::string file = tempPath("eval_app_main_file");
  std::ofstream(file) << "x";
  EXPECT_EQ(exitCode({"-q", "stat_01", "--csv", (file + "/e.csv").c_str()}), 1);
  std::filesystem::remove(file);
}

TEST(EvalApp, BadArgumentsGiveOneLineNamingTheFlag) {
  struct Bad {
    const char* named;  ///< what the message starts with
    std::vector<const char*> args;
  };
  const std::vector<Bad> bad = {{"--seeds", {"--seeds", "2.7"}},
                                {"--jobs", {"--jobs", "-1"}},
                                {"--points", {"--points", "0.5"}},
                                {"--seeds", {"--seeds", "1e11"}},
                                {"--passes", {"--passes", "x"}},
                                {"--duration", {"--duration", "0"}},
                                {"--duration", {"--duration", "nan"}},
                                {"--fail-velocity", {"--fail-velocity", "x"}},
                                {"--gyro-prior", {"--gyro-prior", "-0.1"}},
                                {"--tau", {"--tau", "inf"}},
                                {"--time-offset-sigma", {"--time-offset-sigma", "0.2"}},
                                {"--imu-noise-factor", {"--imu-noise-factor", "0"}},
                                {"--imu-noise-factor", {"--imu-noise-factor", "x"}},
                                {"--imu-noise-factor", {"--imu-noise-factor", "4:0.25"}},
                                {"--imu-noise-factor", {"--imu-noise-factor", "0.25:"}},
                                {"--imu-noise-factor", {"--imu-noise-factor", "1:200"}},
                                {"--doppler-noise-factor", {"--doppler-noise-factor", "nan"}},
                                {"--doppler-noise-factor", {"--doppler-noise-factor", "-2"}},
                                {"--doppler-noise-factor", {"--doppler-noise-factor"}},
                                {"--time-offset", {"--time-offset", "-0.001"}},
                                {"--time-offset", {"--time-offset", "0.2"}},
                                {"--time-offset", {"--time-offset", "0.01:0.001"}},
                                {"--time-offset", {"--time-offset", "1:2:3"}},
                                {"--md", {"--md"}},
                                {"--csv", {"--csv", "--md", "x"}},
                                {"--bogus", {"dyna_04", "--bogus"}},
                                {"nopreset", {"-q", "nopreset"}}};
  for (const Bad& b : bad) {
    SCOPED_TRACE(b.named);
    EvalApp app;
    app.params.seeds = 7;
    try {
      parseLine(app, b.args);
      ADD_FAILURE() << "no error";
    } catch (const EvalApp::UsageError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(std::string(b.named) + ": ", 0), 0u) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
    EXPECT_EQ(app.params.seeds, 7);  // unchanged
  }
}

TEST(EvalApp, ATinyRunGivesARowPerMethodAndTheFiles) {
  EvalApp app;
  const std::string dir = tempPath("eval_app");
  std::filesystem::remove_all(dir);
  ASSERT_EQ(
      parseLine(app, {"-q", "--seeds", "1", "--jobs", "1", "--points", "2000", "--duration", "1.0",
                      "--dlio-duration", "0.8", "stat_01", "--csv", (dir + "/sub/e.csv").c_str()}),
      EvalApp::Action::Run);
  std::ostringstream out, progress;
  app.run(out, progress);
  ASSERT_EQ(app.rows.size(), 4u);
  const char* const names[] = {"free-init", "fast-lio2", "dlio", "doppler-ls"};
  for (std::size_t i = 0; i < app.rows.size(); ++i) {
    EXPECT_EQ(app.rows[i].source, "stat_01");
    EXPECT_EQ(app.rows[i].seed, 1);
    EXPECT_EQ(app.rows[i].method, names[i]);
    EXPECT_EQ(app.rows[i].status, "ok");
  }
  EXPECT_FALSE(app.rows[0].failed) << app.rows[0].failure;
  EXPECT_EQ(progress.str(), "done stat_01 seed 1\n");
  EXPECT_EQ(out.str().find("free-init  stat_01"), std::string::npos);  // -q: no per-run lines
  EXPECT_NE(out.str().find("stat_01"), std::string::npos);             // the summary
  const auto back = readEvalCsv(dir + "/sub/e.csv");
  ASSERT_EQ(back.size(), 4u);
  EXPECT_EQ(back[3].method, "doppler-ls");
  std::filesystem::remove_all(dir);
}

// A run handed wrong noise: the estimator gets the datasheet noise over the factor, the row says
// what it was handed and what the truth is, and the bound stays the true noise's.
TEST(EvalApp, TheRowSaysWhatTheEstimatorWasHandedAndTheTruth) {
  const std::string csv = tempPath("eval_factors.csv");
  std::vector<EvalRow> by_factor[2];
  const char* const factors[2] = {"1", "4"};
  for (int k = 0; k < 2; ++k) {
    EvalApp app;
    ASSERT_EQ(parseLine(app, {"-q", "--seeds", "1", "--jobs", "1", "--no-baselines", "--points",
                              "2000", "--duration", "0.6", "stat_01", "--imu-noise-factor",
                              factors[k], "--csv", csv.c_str()}),
              EvalApp::Action::Run);
    std::ostringstream out, progress;
    app.run(out, progress);
    ASSERT_EQ(app.rows.size(), 1u);
    by_factor[k] = readEvalCsv(csv);
    EXPECT_NE(out.str().find("| free-init · imu×" + std::string(factors[k]) + " | 1 / 1 |"),
              std::string::npos)
        << out.str();
  }
  std::filesystem::remove(csv);
  const sim::ScenarioConfig sc = sim::preset("stat_01", 1);
  for (int k = 0; k < 2; ++k) {
    const EvalRow& r = by_factor[k][0];
    const double f = k == 0 ? 1 : 4;
    EXPECT_EQ(r.status, "ok");
    EXPECT_EQ(r.imu_noise_factor, f);
    EXPECT_EQ(r.doppler_noise_factor, 1.0);
    EXPECT_NEAR(r.noise_gyro.declared, sc.gyro_sigma / f, 1e-12);
    EXPECT_NEAR(r.noise_accel.declared, sc.accel_sigma / f, 1e-12);
    EXPECT_NEAR(r.noise_doppler.declared, sc.doppler_sigma, 1e-12);
    EXPECT_NEAR(r.noise_gyro.truth, sc.gyroSigmaPerAxis().norm() / std::sqrt(3.0), 1e-12);
    EXPECT_NEAR(r.noise_doppler.truth, sc.doppler_sigma, 1e-12);
    // Read at rest from the window's samples, whatever the factor (about 100 samples x 3 axes: a
    // relative sigma near 5 %, so 25 % is beyond 4 sigma).
    EXPECT_NEAR(r.noise_gyro.reported, r.noise_gyro.truth, 0.25 * r.noise_gyro.truth);
    EXPECT_EQ(r.time_offset_true, 0.0);
    // A static preset: at rest over the whole window, with its zero-rate bound.
    EXPECT_TRUE(r.staticWindow()) << r.rest_samples << " of " << r.window_samples;
    EXPECT_NEAR(
        r.crb_gyro_bias_zero_rate,
        eval::zeroRateGyroBiasBound(sc.gyroSigmaPerAxis(), static_cast<std::size_t>(r.rest_samples),
                                    FreeInitConfig{}.imu.gyro_bias_sigma0),
        1e-12);
  }
  // The bound is the truth's: the same whatever the estimator was told.
  EXPECT_EQ(by_factor[0][0].crb_velocity, by_factor[1][0].crb_velocity);
  EXPECT_EQ(by_factor[0][0].crb_gyro_bias, by_factor[1][0].crb_gyro_bias);
}

// An output folder that cannot be created fails before any run, naming its option.
TEST(EvalApp, AnOutputFolderThatCannotBeMadeFailsFirst) {
  const std::string file = tempPath("eval_app_file");
  std::ofstream(file) << "x";
  EvalApp app;
  app.params.presets = {"stat_01"};
  app.params.md = file + "/e.md";
  std::ostringstream out, progress;
  try {
    app.run(out, progress);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--md: cannot create the folder " + file, 0), 0u)
        << e.what();
  }
  EXPECT_TRUE(progress.str().empty());
  EXPECT_TRUE(app.rows.empty());
  std::filesystem::remove(file);
}

}  // namespace
}  // namespace freeinit::report
