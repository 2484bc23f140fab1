#!/usr/bin/env bash
# Free-Init online over loopback: freeinit-online listens, freeinit-stream plays a recording in
# real time, the state is written the moment the window closes; then `freeinit` runs offline on
# what freeinit-online recorded and the two initial_state.ini files are compared.
#
#   ./scripts/run_live_demo.sh [SOURCE] [OUT_DIR] [PORT]
#
#   SOURCE   a simulator preset (e.g. dyna_05), or a .rawlog (default rawlogs/dyna_01.rawlog)
#   OUT_DIR  output folder (default out/live); the offline run goes to OUT_DIR/offline. As the
#            apps do, the script replaces only what it writes there (the apps' outputs, its
#            online.log and offline.log); a user's files stay, and an earlier live recording is
#            kept under another name by freeinit-online.
#   PORT     UDP port on 127.0.0.1 (default 47800)
# Environment: BUILD_DIR (default build), POINTS (points per frame for a preset, default 60000),
#   STREAM_ARGS (more freeinit-stream options, e.g. "--drop 0.0005 --reorder 0.02 --duplicate 0.02";
#   a frame of 60,000 points is ~200 datagrams and is dropped whole if one of them is lost).
set -euo pipefail
cd "$(dirname "$0")/.."

die() { echo "[live] error: $*" >&2; exit 1; }
usage() { sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'; }
case "${1:-}" in -h|--help) usage; exit 0 ;; esac
[ $# -le 3 ] || { usage >&2; die "too many arguments"; }
source=${1:-rawlogs/dyna_01.rawlog}
out=${2:-out/live}
port=${3:-47800}
BUILD_DIR=${BUILD_DIR:-build}
bin=$BUILD_DIR/bin
for b in freeinit freeinit-online freeinit-stream; do
  [ -x "$bin/$b" ] || die "$bin/$b not built: run ./scripts/setup.sh first"
done
if [[ "$source" == *.rawlog ]]; then
  [ -f "$source" ] || die "$source not found"
  play=(-i "$source")
else
  play=(-P "$source" -n "${POINTS:-60000}" -d 1.0)
fi

mkdir -p "$out"
echo "[live] $bin/freeinit-online ini/freeinit.ini --port $port --out $out  (log: $out/online.log)"
"$bin/freeinit-online" ini/freeinit.ini --port "$port" --out "$out" --wait 60 > "$out/online.log" 2>&1 &
online=$!
trap 'kill $online 2>/dev/null || true' EXIT
# shellcheck disable=SC2086
"$bin/freeinit-stream" "${play[@]}" --port "$port" --wait-listener 10 ${STREAM_ARGS:-}
rc=0
wait $online || rc=$?
trap - EXIT
grep -E "^(Sender|State written|End of stream|Recorded|Warning|Initialization|Error)" "$out/online.log" ||
  true
[ $rc -eq 0 ] || [ $rc -eq 3 ] || die "freeinit-online failed (exit code $rc), see $out/online.log"

echo "[live] offline on the recording: $bin/freeinit ini/freeinit.ini $out/live.rawlog -o $out/offline -q"
off=0
"$bin/freeinit" ini/freeinit.ini "$out/live.rawlog" -o "$out/offline" -q > "$out/offline.log" 2>&1 ||
  off=$?
if [ $rc -eq 3 ] && [ $off -eq 1 ]; then
  # Live, too little data is a status; offline, a recording too short is refused as input.
  echo "[live] not initialized live ($(grep '^status' "$out/initial_state.ini"));" \
       "offline: $(grep 'error:' "$out/offline.log")"
  exit 0
fi
[ $off -eq $rc ] || die "offline exit code $off differs from the live one ($rc), see $out/offline.log"
if cmp -s "$out/initial_state.ini" "$out/offline/initial_state.ini"; then
  echo "[live] live and offline initial_state.ini are identical"
else
  die "live and offline initial_state.ini differ: diff $out/initial_state.ini $out/offline/initial_state.ini"
fi
