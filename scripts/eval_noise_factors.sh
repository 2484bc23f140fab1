#!/usr/bin/env bash
# Re-measures the README's table "Noise nobody wrote down": Free-Init on randomized scenarios
# (every platform, moving, starting and static starts) with the IMU's and the Doppler's noise
# handed to it wrong by factors drawn per run in [1/4, 4], and every run's LiDAR-IMU clock offset
# undeclared (drawn in 0-10 ms, either sign); writes
#   gui_snapshots/results_noise.md   the table: a row per IMU factor, then per Doppler factor
#   gui_snapshots/eval_noise.csv     every run
# and copies it into README.md between "<!-- results-noise:begin -->" and "... :end -->".
#
#   ./scripts/eval_noise_factors.sh [--no-readme]
#
# Environment: BUILD_DIR (default build; a Release build of freeinit-eval), SEED_BASE (default
# 45100001: a set held out until this table was last made; 44800001 on was used to develop the
# clock offset's column, 44900001 and 45000001 on were held out once each since), RUNS (default
# 300), JOBS (default 0: every core).
set -euo pipefail
cd "$(dirname "$0")/.."
tag=noise
source scripts/eval_common.sh
base=${SEED_BASE:-45100001}
runs=${RUNS:-300}

# One run: both factors drawn per run (log-uniform in [1/4, 4], from a stream of their own), the
# summaries per IMU factor over every Doppler one and per Doppler factor over every IMU one (each
# draw binned to the nearest power of two).
summary=$tmp/summary.csv
"$eval_app" --random "$runs" --seed-base "$base" --no-baselines --duration 0.8 \
  --jobs "${JOBS:-0}" -q --time-offset 0:0.010 --imu-noise-factor 0.25:4 \
  --doppler-noise-factor 0.25:4 --summary-by imu,doppler --summary-csv "$summary" \
  --csv "$out/eval_noise.csv" > /dev/null 2> "$tmp/progress.log" ||
  { cat "$tmp/progress.log" >&2; exit 1; }

# A row per block, from the summary CSV's columns by name.
{
  echo "| true noise / declared | ok / runs | error / bound, median (p95): velocity | gravity | b_g | b_a | NEES > 99.9 % | confident wrong | static b_g > 3× zero-rate bound | noise from the data within 20 % of the truth: gyro, accel, Doppler |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
  for sensor in imu doppler; do
    awk -F, -v sensor="$sensor" '
      NR == 1 { for (i = 1; i <= NF; ++i) col[$i] = i; next }
      index($col["block"], sensor) != 1 { next }
      function v(name) { return $col[name] }
      function q(name) {
        if (v(name "_median") == "" || v(name "_median") == "nan") return "–"
        return sprintf("%.2f (%.2f)", v(name "_median"), v(name "_p95"))
      }
      {
        split(v("block"), words, " ")
        label = words[1]
        sub(/^imu/, "IMU ", label)
        sub(/^doppler/, "Doppler ", label)
        nees = v("nees_velocity_above_chi2_999") + v("nees_tilt_above_chi2_999") + \
               v("nees_gyro_bias_above_chi2_999") + v("nees_accel_bias_above_chi2_999")
        printf "| %s | %d / %d | %s | %s | %s | %s | %d of %d × 4 | %d | %d of %d | %d/%d, %d/%d, %d/%d |\n", \
          label, v("ok"), v("runs"), q("ratio_velocity"), q("ratio_gravity"), \
          q("ratio_gyro_bias"), q("ratio_accel_bias"), nees, v("runs_with_nees"), \
          v("confident_wrong"), v("static_gyro_bias_above_3x_zero_rate"), v("static_starts"), \
          v("noise_gyro_within_20pct"), v("noise_gyro_resolved"), \
          v("noise_accel_within_20pct"), v("noise_accel_resolved"), \
          v("noise_doppler_within_20pct"), v("noise_doppler_resolved")
      }' "$summary"
  done
} > "$tmp/table.md"
# Whole or not at all: an interrupted run leaves the earlier table.
mv "$tmp/table.md" "$out/results_noise.md"
echo "[noise] wrote $out/results_noise.md"
[ "$readme" -eq 1 ] || exit 0

copy_between_markers "$out/results_noise.md" results-noise README.md ||
  { echo "[noise] error: README.md has no <!-- results-noise:begin/end --> markers" >&2; exit 1; }
echo "[noise] README.md: results-noise updated"
