#!/usr/bin/env bash
# Measures the README's table "Fast IMUs": Free-Init on randomized scenarios (every platform and
# kind of start) whose IMU rate is drawn per run, log-uniform in 100-2000 Hz (the per-sample noise
# at the scenario's density), with an undeclared LiDAR-IMU clock offset of 0-10 ms in every run,
# once with a filter node per IMU sample ([joint] node_rate = 0, the default) and once with nodes
# at 200 Hz; writes
#   gui_snapshots/results_imu_rates.md   the table: a row per layout, then their difference
#   gui_snapshots/eval_imu_rates_nodes{0,200}.csv   every run
# and copies it into README.md between "<!-- results-imu-rates:begin -->" and "... :end -->".
#
#   ./scripts/eval_imu_rates.sh [--no-readme]
#
# Environment: BUILD_DIR (default build; a Release build of freeinit-eval), SEED_BASE (default
# 45400001, held out until this table was last made; 45200001 and 45300001 on were used to
# develop the clock offset's column at fast rates), RUNS (default 200), JOBS (default 0: every
# core).
set -euo pipefail
cd "$(dirname "$0")/.."
tag=imu-rates
source scripts/eval_common.sh
base=${SEED_BASE:-45400001}
runs=${RUNS:-200}

for nodes in 0 200; do
  "$eval_app" --random "$runs" --seed-base "$base" --no-baselines --duration 0.8 \
    --jobs "${JOBS:-0}" -q --time-offset 0:0.010 --imu-rate 100:2000 --node-rate "$nodes" \
    --summary-csv "$tmp/summary$nodes.csv" --csv "$out/eval_imu_rates_nodes$nodes.csv" \
    > /dev/null 2> "$tmp/progress.log" || { cat "$tmp/progress.log" >&2; exit 1; }
done

{
  echo "| filter nodes | ok / runs | confident wrong | NEES > 99.9 %: velocity, tilt, b_g, b_a | offset more than 3 σ off |"
  echo "|---|---|---|---|---|"
  for nodes in 0 200; do
    label="one per IMU sample"
    [ "$nodes" -eq 0 ] || label="at $nodes Hz"
    # The offset's misses from the runs (ok, the calibration right), the rest from the summary.
    misses=$(awk -F, '
      NR == 1 { for (i = 1; i <= NF; ++i) col[$i] = i; next }
      $col["status"] != "ok" || $col["wrong_calibration"] == 1 { next }
      { s = $col["time_offset_reported_sigma_s"] + 0; if (s <= 0) next; ++n
        d = $col["time_offset_reported_s"] - $col["time_offset_true_s"]; if (d < 0) d = -d
        if (d > 3 * s) ++m }
      END { printf "%d of %d", m, n }' "$out/eval_imu_rates_nodes$nodes.csv")
    awk -F, -v label="$label" -v misses="$misses" '
      NR == 1 { for (i = 1; i <= NF; ++i) col[$i] = i; next }
      function v(name) { return $col[name] }
      { printf "| %s | %d / %d | %d | %d, %d, %d, %d of %d | %s |\n", label, v("ok"), v("runs"),
          v("confident_wrong"), v("nees_velocity_above_chi2_999"), v("nees_tilt_above_chi2_999"),
          v("nees_gyro_bias_above_chi2_999"), v("nees_accel_bias_above_chi2_999"),
          v("runs_with_nees"), misses }' "$tmp/summary$nodes.csv"
  done
  # The issue's parity: per run ok in both layouts with the calibration right, |error / bound at
  # 200 Hz - error / bound with a node per sample| for each quantity; their median and 90th
  # percentile.
  echo
  echo "| nodes at 200 Hz against one per sample, \\|Δ error\\| / bound | velocity | gravity | b_g | b_a |"
  echo "|---|---|---|---|---|"
  awk -F, '
    FNR == 1 { for (i = 1; i <= NF; ++i) col[$i] = i; ++file; next }
    $col["status"] != "ok" || $col["wrong_calibration"] == 1 { next }
    file == 1 { for (q = 1; q <= 4; ++q) a[$col["seed"], q] = $col["ratio_" name[q]]; has[$col["seed"]] = 1; next }
    has[$col["seed"]] { ++n; for (q = 1; q <= 4; ++q) { d = $col["ratio_" name[q]] - a[$col["seed"], q]; diff[q, n] = d < 0 ? -d : d } }
    BEGIN { name[1] = "velocity"; name[2] = "gravity"; name[3] = "gyro_bias"; name[4] = "accel_bias" }
    END {
      for (q = 1; q <= 4; ++q) {
        for (i = 1; i <= n; ++i) x[i] = diff[q, i]
        for (i = 2; i <= n; ++i) { t = x[i]; for (j = i - 1; j >= 1 && x[j] > t; --j) x[j + 1] = x[j]; x[j + 1] = t }
        med[q] = x[int((n + 1) / 2)]; p90[q] = x[int(0.9 * n + 0.5)]
      }
      printf "| median (90th percentile) over %d runs | %.3f (%.2f) | %.3f (%.2f) | %.3f (%.2f) | %.3f (%.2f) |\n",
        n, med[1], p90[1], med[2], p90[2], med[3], p90[3], med[4], p90[4]
    }' "$out/eval_imu_rates_nodes0.csv" "$out/eval_imu_rates_nodes200.csv"
} > "$tmp/table.md"
# Whole or not at all: an interrupted run leaves the earlier table.
mv "$tmp/table.md" "$out/results_imu_rates.md"
echo "[imu-rates] wrote $out/results_imu_rates.md"
[ "$readme" -eq 1 ] || exit 0

copy_between_markers "$out/results_imu_rates.md" results-imu-rates README.md ||
  { echo "[imu-rates] error: README.md has no <!-- results-imu-rates:begin/end --> markers" >&2; exit 1; }
echo "[imu-rates] README.md: results-imu-rates updated"
