#!/usr/bin/env bash
# The cost of the window, not of the file (outside CI: the 5 min recording is ~3.5 GB):
#  1. the same initialization on a 30 s and on a 5 min recording at the sensor's density
#     (dyna_05, 60,000 points per frame): wall time and peak resident memory;
#  2. reaching a start 4 min into the 5 min recording: without an index (everything before it is
#     decompressed and deserialized), while writing the index, and with it;
#  3. what reading the whole 5 min file costs (--check-all), for scale.
# Usage: scripts/bench_window_cost.sh [BUILD_DIR] [RUNS]   (from the repository root; the files
# go to ${TMPDIR:-/tmp}/freeinit_bench_window and are deleted at the end unless KEEP=1).
set -euo pipefail
BUILD=${1:-build}
RUNS=${2:-3}
DIR=${TMPDIR:-/tmp}/freeinit_bench_window
mkdir -p "$DIR"
[ "${KEEP:-0}" = 1 ] || trap 'rm -rf "$DIR"' EXIT
APP=$BUILD/bin/freeinit
INI=ini/freeinit.ini

for d in 30 300; do
  if [ ! -f "$DIR/d$d.rawlog" ]; then
    echo "simulating $d s of dyna_05 at 60,000 points per frame..."
    "$BUILD/bin/freeinit-sim" -p dyna_05 -d "$d" -n 60000 -o "$DIR/d$d.rawlog" > /dev/null
  fi
done
ls -l "$DIR"/d30.rawlog "$DIR"/d300.rawlog

# label, then freeinit's arguments after the INI; prints wall [s] and peak RSS [MB] of each run.
run() {
  local label=$1
  shift
  for i in $(seq "$RUNS"); do
    /usr/bin/time -f "%e %M" -o "$DIR/time" "$APP" "$INI" "$@" -q -o "$DIR/out" > "$DIR/log"
    read -r wall rss < "$DIR/time"
    printf "%-48s run %d: %6.2f s  %5d MB\n" "$label" "$i" "$wall" $((rss / 1024))
  done
}

rm -f "$DIR"/*.freeinit.idx
run "30 s recording, start of file" "$DIR/d30.rawlog" --no-index
run "5 min recording, start of file" "$DIR/d300.rawlog" --no-index
run "5 min, --start 240, no index" "$DIR/d300.rawlog" --start 240 --no-index
RUNS=1 run "5 min, --start 240, first read (writes index)" "$DIR/d300.rawlog" --start 240
ls -l "$DIR"/d300.rawlog.freeinit.idx
run "5 min, --start 240, with the index" "$DIR/d300.rawlog" --start 240
RUNS=1 run "5 min, --check-all (whole file)" "$DIR/d300.rawlog" --check-all --no-index
