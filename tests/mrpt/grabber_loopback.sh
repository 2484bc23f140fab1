#!/usr/bin/env bash
# ctest: the real rawlog-grabber with our driver, headless, records freeinit-stream's playback of
# the committed sample over loopback; the rawlog holds every cloud and is accepted by `freeinit`.
#   grabber_loopback.sh SOURCE_DIR BUILD_DIR PORT
set -euo pipefail
src=$1; build=$2; port=$3
out=$(mktemp -d /tmp/freeinit_grabber_test.XXXXXX)
trap 'rm -rf "$out"' EXIT
cd "$src"
# The stop key goes to rawlog-grabber 1.5 s after the stream ended (time to write its queue).
( "$build/bin/freeinit-stream" -i rawlogs/dyna_01.rawlog -p "$port" -w 20 -x 2 >&2
  sleep 1.5; echo ) | BUILD_DIR=$build ./scripts/grab_live.sh - "$out" "$port" > "$out/grab.log" 2>&1 ||
  { cat "$out/grab.log"; exit 1; }
rawlog=$(tail -1 "$out/grab.log")
info=$(rawlog-edit -p "$build/lib/libfreeinit_mrpt_plugins.so" --info -i "$rawlog" 2>&1)
echo "$info" | grep -E "IMU|LIDAR"
echo "$info" | grep -qE "LIDAR */ *15 " || { echo "expected the 15 clouds"; exit 1; }
imu=$(echo "$info" | sed -nE 's/.* IMU *\/ *([0-9]+) .*/\1/p')
sent=$(sed -nE 's/^imu_samples *= *([0-9]+).*/\1/p' "$out/stream_stats.ini")
anomalies=$(grep -E "^(lost|malformed|duplicates|frames_incomplete|queue_dropped_imu|queue_dropped_frames) *=" "$out/stream_stats.ini" | awk -F= '{s+=$2} END {print s}')
echo "driver received $sent IMU samples, the rawlog holds $imu; anomalies: $anomalies"
[ "$sent" = 301 ] && [ "$anomalies" = 0 ] || { cat "$out/stream_stats.ini"; exit 1; }
# rawlog-grabber 2.5.8 writes half of its pending list per period and, at exit, half of what is
# left: the newest object or so may be missing from the file (not a loss of the driver's).
[ "$imu" -ge 300 ] || { echo "too few IMU samples in the rawlog"; exit 1; }
"$build/bin/freeinit" ini/freeinit.ini "$rawlog" -o "$out/freeinit" -q | grep "Initialization: ok"
