#!/usr/bin/env bash
# Live faults on loopback: freeinit-online fed by freeinit-stream through reordered, duplicated,
# truncated, corrupted and lost datagrams, floods (garbage and data as fast as possible), two
# senders at once, signals at random moments (SIGINT, SIGTERM, SIGHUP; SIGKILL and the next run)
# and a disk that fills. Each case asserts that the run ends (every wait and every process is
# bounded), with a correct state or a readable recording, and a clear message:
#   - exit 0: status ok, and `freeinit` on the recording writes the same initial_state.ini; a
#     stream that lost nothing gives the state of `freeinit` on the sample itself;
#   - exit 3: a status that says why, and a recording that reads without error;
#   - exit 1: one line on stderr, no MRPT exception text; the recording, if any, reads;
#   - no staging folder, lock or temporary file of ours is left behind.
#
#   tests/live_faults.sh [--quick | --long [ROUNDS]] [--seed N] [--build DIR] [--work DIR]
#
#   --quick      one case of each kind, under a minute (what ctest runs; the default)
#   --long N     N rounds (default 10) of every kind with random fault rates, signal moments and
#                disk sizes drawn from --seed; ends with a table of figures
#   --seed N     seed of the draws (default 1): a run is repeatable
#   --build DIR  the build folder (default build); --work DIR where runs go (default out/live_faults)
# The full-disk case needs a private mount namespace (root, unshare): skipped otherwise.
set -uo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)

mode=quick rounds=1 seed=1 build=$src/build work=$src/out/live_faults
while [ $# -gt 0 ]; do
  case $1 in
    --quick) mode=quick rounds=1 ;;
    --long) mode=long rounds=10
      if [[ ${2:-} =~ ^[0-9]+$ ]]; then rounds=$2; shift; fi ;;
    --seed) seed=$2; shift ;;
    --build) build=$2; shift ;;
    --work) work=$2; shift ;;
    -h|--help) sed -n '2,21p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "live_faults.sh: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
  shift
done
bin=$build/bin
for b in freeinit freeinit-online freeinit-stream; do
  [ -x "$bin/$b" ] || { echo "live_faults.sh: $bin/$b not built" >&2; exit 2; }
done
sample=$src/rawlogs/dyna_01.rawlog
RANDOM=$seed
rm -rf "$work"
mkdir -p "$work"
# The configuration of every run (live, offline, reference). Quick: without the PNG snapshots and
# the simplemap, the slowest outputs to write; long: the defaults.
ini=$src/ini/freeinit.ini
if [ "$mode" = quick ]; then
  sed -e 's/^;snapshots *=.*/snapshots = false/' -e 's/^;simplemap *=.*/simplemap = false/' \
    "$ini" > "$work/freeinit.ini"
  ini=$work/freeinit.ini
fi

# Bounds [s]: a stream, a run, a wait for a port.
stream_limit=60
run_limit=90
port_wait_steps=1000  # x 0.01 s

pass=0 fail=0 skip=0
declare -A runs exits identical_offline identical_sample recordings_read
note() { printf '%s\n' "$*"; }
failed() { note "  FAIL: $*"; case_ok=0; }

# Random integer in [lo, hi], and a probability (0.xxx) up to `max_permille`/1000.
draw() { echo $(( $1 + RANDOM % ($2 - $1 + 1) )); }
prob() { printf '0.%03d' "$(draw 1 "$1")"; }

# Starts freeinit-online on $1 with idle timeout $2 s in the background; sets online_pid, port.
start_online() {
  local out=$1 idle=$2
  mkdir -p "$(dirname "$out")"
  "$bin/freeinit-online" "$ini" -o "$out" -p 0 -i "$idle" -w 10 -d "$stream_limit" \
    > "$out.log" 2> "$out.err" &
  online_pid=$!
  port=
  local i
  for ((i = 0; i < port_wait_steps; ++i)); do
    port=$(sed -n 's/.*Listening on UDP 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$out.log" 2>/dev/null)
    [ -n "$port" ] && return 0
    kill -0 "$online_pid" 2>/dev/null || return 1
    sleep 0.01
  done
  return 1
}

stream() { timeout -s KILL "$stream_limit" "$bin/freeinit-stream" "$@" >> "$work/stream.log" 2>&1; }

# Waits for the process $1 at most $2 s (then kills it: a failure); returns its exit status.
wait_bounded() {
  local pid=$1 limit=$2 i
  for ((i = 0; i < limit * 20; ++i)); do
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.05
  done
  if kill -0 "$pid" 2>/dev/null; then
    kill -s KILL "$pid" 2>/dev/null
    failed "pid $pid did not end within $limit s"
  fi
  wait "$pid"
}

# One line at most, no MRPT exception text, no crash text.
check_message() {
  local err=$1
  local lines
  lines=$(wc -l < "$err")
  [ "$lines" -le 1 ] || failed "$lines lines on stderr: $(head -3 "$err")"
  if grep -qE "MRPT exception|====|backtrace|terminate called|Segmentation|Aborted" "$err"; then
    failed "not a clear message: $(head -1 "$err")"
  fi
}

# The recording reads without error (strict reader): `freeinit` on it may refuse it as too
# short, never as cut or corrupt.
check_readable() {
  local rec=$1 tag=$2
  local rc=0
  timeout -s KILL "$run_limit" "$bin/freeinit" "$ini" "$rec" -q -o "$work/$tag.offline" \
    > "$work/$tag.offline.log" 2> "$work/$tag.offline.err" || rc=$?
  if grep -qiE "truncat|corrupt|ends inside|cannot be read|CRC" "$work/$tag.offline.err"; then
    failed "$rec does not read: $(head -1 "$work/$tag.offline.err")"
    return 1
  fi
  case $rc in 0|1|3) ;; *) failed "freeinit on $rec: exit code $rc"; return 1 ;; esac
  recordings_read[$kind]=$(( ${recordings_read[$kind]:-0} + 1 ))
  offline_rc=$rc
  return 0
}

# What a run on $out ended with ($rc): the rules of the header.
check_outcome() {
  local out=$1 rc=$2 tag=$3 lossless=${4:-0}
  check_message "$out.err"
  if [ -e "$out/.freeinit.staging" ] || [ -e "$out/.freeinit.lock" ] ||
     [ -n "$(find "$out" -name '*.tmp' 2>/dev/null)" ]; then
    failed "staging, lock or temporary file left in $out"
  fi
  case $rc in
    0)
      grep -q '^status *= *ok' "$out/initial_state.ini" 2>/dev/null || failed "exit 0 without status ok"
      if check_readable "$out/live.rawlog" "$tag"; then
        if [ "$offline_rc" = 0 ] && cmp -s "$out/initial_state.ini" "$work/$tag.offline/initial_state.ini"; then
          identical_offline[$kind]=$(( ${identical_offline[$kind]:-0} + 1 ))
        else
          failed "freeinit on the recording (exit $offline_rc) does not give the live state"
        fi
      fi
      local anomalies
      anomalies=$(grep -E "^(lost|late|frames_incomplete|frames_inconsistent|queue_dropped_imu|queue_dropped_frames|imu_stale|frames_stale) *=" \
        "$out/stream_stats.ini" 2>/dev/null | awk -F= '{s += $2} END {print s + 0}')
      if [ "$lossless" = 1 ] && [ "$anomalies" = 0 ]; then
        if cmp -s "$out/initial_state.ini" "$work/reference/initial_state.ini"; then
          identical_sample[$kind]=$(( ${identical_sample[$kind]:-0} + 1 ))
        else
          failed "nothing was lost, yet the state differs from freeinit's on the sample"
        fi
      fi
      ;;
    3)
      if grep -q '^status *= *ok' "$out/initial_state.ini" 2>/dev/null; then
        failed "exit 3 with status ok"
      fi
      [ -s "$out/live.rawlog" ] && check_readable "$out/live.rawlog" "$tag"
      ;;
    1)
      [ -s "$out.err" ] || failed "exit 1 without a message"
      local rec
      for rec in "$out"/live*.rawlog; do
        [ -e "$rec" ] && check_readable "$rec" "$tag.$(basename "$rec" .rawlog)"
      done
      ;;
    *) failed "exit code $rc: $(head -1 "$out.err")" ;;
  esac
}

begin_case() {
  kind=$1 case_ok=1 label=$2
  runs[$kind]=$(( ${runs[$kind]:-0} + 1 ))
  t_case=$(date +%s.%N)
}
end_case() {
  local rc=$1
  exits[$kind]="${exits[$kind]:-} $rc"
  local secs
  secs=$(awk -v a="$t_case" -v b="$(date +%s.%N)" 'BEGIN {printf "%.1f", b - a}')
  if [ "$case_ok" = 1 ]; then
    pass=$((pass + 1)); note "[pass] $kind: $label: exit $rc ($secs s)"
  else
    fail=$((fail + 1)); note "[FAIL] $kind: $label: exit $rc ($secs s), see $work"
  fi
}

# A stream at speed $3 through network faults ($@ after it: freeinit-stream's fault options);
# $2 = 1: faults that lose nothing, so that the state must be the sample's.
network_case() {
  local name=$1 lossless=$2 speed=$3; shift 3
  local out=$work/$name.$round
  begin_case "$name" "$* at ${speed}x"
  if ! start_online "$out" 1; then failed "freeinit-online did not listen"; end_case none; return; fi
  stream -i "$sample" -p "$port" -x "$speed" --fault-seed "$(draw 1 100000)" "$@"
  local rc=0
  wait_bounded "$online_pid" "$run_limit" || rc=$?
  check_outcome "$out" "$rc" "$name.$round" "$lossless"
  end_case "$rc"
}

two_senders_case() {
  local out=$work/two_senders.$round
  begin_case two_senders "the sample and a preset at once"
  if ! start_online "$out" 1; then failed "freeinit-online did not listen"; end_case none; return; fi
  stream -i "$sample" -p "$port" -x 2 --no-end-marker &
  local other=$!
  stream -P dyna_05 -n 4000 -d 1.5 -p "$port" -x 2 --no-end-marker
  wait "$other"
  local rc=0
  wait_bounded "$online_pid" "$run_limit" || rc=$?
  check_outcome "$out" "$rc" "two_senders.$round"
  end_case "$rc"
}

# Sleeps $2 ms after the first data reached the run on $1 (its log says so; at most 10 s of
# waiting for them); a negative $2: at once, before any data.
after_first_data() {
  local out=$1 delay_ms=$2 i
  [ "$delay_ms" -lt 0 ] && return 0
  for ((i = 0; i < 1000; ++i)); do
    grep -q "^Sender session" "$out.log" 2>/dev/null && break
    sleep 0.01
  done
  sleep "$(awk -v m="$delay_ms" 'BEGIN {print m / 1000}')"
}

# SIGINT, SIGTERM or SIGHUP at a random moment of the stream (or before it): its end.
signal_case() {
  local sig=$1 delay_ms=$2
  local out=$work/signal_$sig.$round
  begin_case "signal" "SIG$sig $delay_ms ms into the stream"
  if ! start_online "$out" 30; then failed "freeinit-online did not listen"; end_case none; return; fi
  stream -i "$sample" -p "$port" -x 1 &
  local sender=$!
  after_first_data "$out" "$delay_ms"
  kill -s "$sig" "$online_pid" 2>/dev/null
  local rc=0
  wait_bounded "$online_pid" "$run_limit" || rc=$?
  wait "$sender"
  check_outcome "$out" "$rc" "signal_$sig.$round"
  if [ "$rc" != 1 ] && ! grep -q "stopped_by *= *SIG$sig" "$out/stream_stats.ini" 2>/dev/null &&
     grep -q "Stopped by SIG$sig" "$out.log"; then
    failed "stream_stats.ini does not say stopped_by = SIG$sig"
  fi
  end_case "$rc"
}

# SIGKILL at a random moment, then a run that receives nothing: the killed run's recording is
# kept (it reads with --salvage), the earlier state is not removed.
kill_case() {
  local delay_ms=$1
  local out=$work/kill.$round
  begin_case "sigkill" "SIGKILL $delay_ms ms into the stream, then a run without data"
  if ! start_online "$out" 30; then failed "freeinit-online did not listen"; end_case none; return; fi
  stream -i "$sample" -p "$port" -x 1 &
  local sender=$!
  after_first_data "$out" "$delay_ms"
  kill -s KILL "$online_pid" 2>/dev/null
  wait "$online_pid" 2>/dev/null
  wait "$sender"
  local state_before=
  [ -f "$out/initial_state.ini" ] && state_before=$(cat "$out/initial_state.ini")
  local rc=0
  timeout -s KILL "$run_limit" "$bin/freeinit-online" "$ini" -o "$out" -p 0 -w 0.3 \
    > "$out.next.log" 2> "$out.next.err" || rc=$?
  check_message "$out.next.err"
  [ "$rc" = 1 ] || failed "the run without data: exit $rc"
  grep -q "no data received" "$out.next.err" || failed "the run without data says: $(cat "$out.next.err")"
  local now=
  [ -f "$out/initial_state.ini" ] && now=$(cat "$out/initial_state.ini")
  [ "$now" = "$state_before" ] || failed "the killed run's state changed under the next run"
  local kept
  kept=$(sed -n 's/^Kept the recording of an interrupted run as \([^ ]*\) .*/\1/p' "$out.next.log")
  if [ -n "$kept" ]; then
    local src_rc=0
    timeout -s KILL "$run_limit" "$bin/freeinit" "$ini" "$kept" -q --salvage -o "$work/kill.$round.salvage" \
      > "$work/kill.$round.salvage.log" 2> "$work/kill.$round.salvage.err" || src_rc=$?
    case $src_rc in 0|1|3) recordings_read[$kind]=$(( ${recordings_read[$kind]:-0} + 1 )) ;;
      *) failed "--salvage on $kept: exit $src_rc" ;; esac
    check_message "$work/kill.$round.salvage.err"
  fi
  [ -e "$out/.freeinit.staging" ] && failed "staging folder left"
  end_case "$rc"
}

# The disk fills while the stream is recorded (a tmpfs of $1 in a private mount namespace).
disk_case() {
  local size=$1
  local d=$work/disk.$round
  begin_case "full_disk" "a $size disk"
  mkdir -p "$d/mnt"
  local out=$d/mnt/out log=$d/online.log
  # The script runs inside the namespace; what the run left is copied out before it ends.
  local script="mount -t tmpfs -o size=$size none $d/mnt 2>/dev/null || exit 77
    timeout -s KILL $run_limit $bin/freeinit-online $ini -o $out -p 0 -i 1 -w 10 -d $stream_limit > $log 2> $d/online.err & pid=\$!
    port=; i=0
    while [ \$i -lt $port_wait_steps ]; do
      port=\$(sed -n 's/.*Listening on UDP 127\\.0\\.0\\.1:\\([0-9]*\\).*/\\1/p' $log)
      [ -n \"\$port\" ] && break; kill -0 \$pid 2>/dev/null || break; sleep 0.01; i=\$((i + 1))
    done
    [ -n \"\$port\" ] && timeout -s KILL $stream_limit $bin/freeinit-stream -P dyna_01 -d 3 -n 8000 -x 2 -p \$port >> $work/stream.log 2>&1
    rc=0; wait \$pid || rc=\$?; echo \$rc > $d/rc; cp -a $out $d/left"
  unshare -m sh -c "$script"
  local st=$?
  if [ "$st" = 77 ] || [ ! -f "$d/rc" ]; then
    skip=$((skip + 1)); runs[$kind]=$(( ${runs[$kind]} - 1 ))
    note "[skip] full_disk: no private tmpfs here (not root?)"
    return
  fi
  local rc
  rc=$(cat "$d/rc")
  cp "$d/online.err" "$d/left.err"
  cp "$log" "$d/left.log"
  check_outcome "$d/left" "$rc" "disk.$round"
  if [ "$rc" = 1 ] && grep -q "the recording stopped" "$d/left.err"; then
    grep -q "no space left on the device" "$d/left.err" || failed "the message does not say the disk is full"
    grep -qs "^recording_stopped *= *no space" "$d"/left/*stream_stats.ini ||
      failed "stream_stats.ini does not say why the recording stopped"
  fi
  end_case "$rc"
}

note "Live faults ($mode, seed $seed, $rounds round(s)): runs in $work"
# The state freeinit gives on the sample: what a stream that lost nothing must give live.
"$bin/freeinit" "$ini" "$sample" -q -o "$work/reference" > "$work/reference.log" 2>&1 ||
  { echo "live_faults.sh: freeinit on the sample failed" >&2; exit 1; }

t0=$(date +%s)
for ((round = 1; round <= rounds; ++round)); do
  if [ "$mode" = quick ]; then
    network_case reorder_duplicate 1 2 --reorder 0.05 --duplicate 0.05
    network_case truncate_drop_corrupt 0 2 --truncate 0.002 --drop 0.002 --corrupt 0.002
    network_case garbage_flood 1 2 --garbage 20000
    network_case data_flood 0 0 --reorder 0.01
    two_senders_case
    signal_case INT "$(draw 100 1200)"
    kill_case "$(draw 100 1200)"
    disk_case 2m
  else
    network_case reorder_duplicate 1 1 --reorder "$(prob 200)" --duplicate "$(prob 200)"
    network_case truncate_drop_corrupt 0 1 --truncate "$(prob 20)" --drop "$(prob 20)" \
      --corrupt "$(prob 20)"
    network_case garbage_flood 1 1 --garbage "$(draw 10000 100000)"
    network_case data_flood 0 0 --reorder "$(prob 50)" --duplicate "$(prob 50)"
    network_case restart 0 1 --restart-at "0.$(draw 1 9)"
    two_senders_case
    signal_case "$(echo INT TERM HUP | cut -d' ' -f"$(draw 1 3)")" "$(draw -200 1800)"
    kill_case "$(draw -200 1800)"
    disk_case "$(draw 300 3000)k"
  fi
done
elapsed=$(( $(date +%s) - t0 ))

note ""
note "case                  runs  exit codes                      live=offline  live=sample  recordings read"
for k in reorder_duplicate truncate_drop_corrupt garbage_flood data_flood restart two_senders signal sigkill full_disk; do
  [ "${runs[$k]:-0}" -gt 0 ] || continue
  codes=$(tr ' ' '\n' <<< "${exits[$k]:-}" | grep -v '^$' | sort | uniq -c |
    awk '{printf "%sx%s ", $1, $2}')
  printf '%-21s %4d  %-31s %12d %12d %16d\n' "$k" "${runs[$k]}" "$codes" \
    "${identical_offline[$k]:-0}" "${identical_sample[$k]:-0}" "${recordings_read[$k]:-0}"
done
note "$pass passed, $fail failed, $skip skipped in $elapsed s"
[ "$fail" = 0 ]
