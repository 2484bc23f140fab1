#!/usr/bin/env bash
# Records a live Doppler LiDAR + IMU stream (docs/wire_format.md) with MRPT's rawlog-grabber and
# our driver, headless, for a fixed time. rawlog-grabber stops on a key from stdin (with
# </dev/null it would exit at once): the key is sent through a pipe after SECONDS.
#
#   ./scripts/grab_live.sh SECONDS [OUT_DIR] [PORT]
#
#   SECONDS  how long to record, or - to stop at the first line on this script's stdin, e.g.
#            ( freeinit-stream -w 10 ...; sleep 1.5; echo ) | ./scripts/grab_live.sh - out/grab
#   OUT_DIR  where the rawlog goes (default out/grab); its name is dataset_doppler_<date>.rawlog
#   PORT     UDP port (default: the INI's, 47800)
# Environment: BUILD_DIR (default build), INI (default ini/rawlog_grabber_doppler_udp.ini).
# Play something to it meanwhile, e.g. build/bin/freeinit-stream -i rawlogs/dyna_01.rawlog
# Prints the rawlog path on the last line; the driver's final statistics go to OUT_DIR/stream_stats.ini.
set -euo pipefail
cd "$(dirname "$0")/.."

die() { echo "[grab] error: $*" >&2; exit 1; }
usage() { sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'; }
case "${1:-}" in -h|--help) usage; exit 0 ;; esac
[ $# -ge 1 ] && [ $# -le 3 ] || { usage >&2; die "expected SECONDS [OUT_DIR] [PORT]"; }
secs=$1
out=${2:-out/grab}
port=${3:-}
[ "$secs" = - ] || [[ "$secs" =~ ^[0-9]+([.][0-9]+)?$ ]] || die "SECONDS must be a number or -, not '$secs'"
[ -z "$port" ] || [[ "$port" =~ ^[0-9]+$ ]] || die "PORT must be a number, not '$port'"

BUILD_DIR=${BUILD_DIR:-build}
plugin=$BUILD_DIR/lib/libfreeinit_mrpt_plugins.so
ini=${INI:-ini/rawlog_grabber_doppler_udp.ini}
[ -f "$plugin" ] || die "$plugin not found: build first (./scripts/setup.sh)"
[ -f "$ini" ] || die "$ini not found"
command -v rawlog-grabber >/dev/null || die "rawlog-grabber not found (package mrpt-apps)"

mkdir -p "$out"
out_abs=$(cd "$out" && pwd)
# The INI with the output folder, the statistics file and the port filled in.
cfg="$out_abs/rawlog_grabber.ini"
sed -e "s|^rawlog_prefix *=.*|rawlog_prefix = $out_abs/dataset_doppler|" \
    -e "s|^stats_file *=.*|stats_file = $out_abs/stream_stats.ini|" \
    ${port:+-e "s|^port *=.*|port = $port|"} "$ini" > "$cfg"
before=$(ls "$out_abs"/dataset_doppler_*.rawlog 2>/dev/null || true)

# rawlog-grabber (MRPT 2.5.8) writes half of its pending objects every GRABBER_PERIOD_MS and only
# half of what is left when it stops: stop it a second or so after the data of interest.
if [ "$secs" = - ]; then
  echo "[grab] recording until a line arrives on stdin, with $cfg"
  rawlog-grabber -p "$plugin" "$cfg"
else
  echo "[grab] recording for $secs s with $cfg"
  ( sleep "$secs"; echo ) | rawlog-grabber -p "$plugin" "$cfg"
fi

rawlog=$(ls -t "$out_abs"/dataset_doppler_*.rawlog 2>/dev/null | head -1 || true)
[ -n "$rawlog" ] && ! grep -qxF "$rawlog" <<<"$before" || die "rawlog-grabber wrote no rawlog"
echo "[grab] wrote $rawlog"
echo "$rawlog"
