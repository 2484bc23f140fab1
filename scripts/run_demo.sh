#!/usr/bin/env bash
# The main job: installs what is missing and builds (./scripts/setup.sh), runs the `freeinit` app
# on an embedded sample rawlog with ini/freeinit.ini, and shows what it wrote.
#
#   ./scripts/run_demo.sh [SAMPLE] [OUT_DIR]
#
#   SAMPLE   dyna_01 (default: handheld rotational start) or stat_01 (static start), i.e. any
#            rawlogs/<name>.rawlog, or a path to a .rawlog file
#   OUT_DIR  output folder (default: out/<sample name>)
# Environment: BUILD_DIR (default build, as for setup.sh), JOBS, SKIP_SETUP=1 (use an existing build).
set -euo pipefail
cd "$(dirname "$0")/.."

die() { echo "[demo] error: $*" >&2; exit 1; }
usage() { sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//'; }

for a in "$@"; do
  case "$a" in
    -h|--help) usage; exit 0 ;;
    -*) usage >&2; die "unknown option '$a'" ;;
  esac
done
[ $# -le 2 ] || { usage >&2; die "too many arguments: $*"; }
sample=${1:-dyna_01}
if [ -f "rawlogs/$sample.rawlog" ]; then rawlog="rawlogs/$sample.rawlog"
elif [[ "$sample" == *.rawlog ]]; then rawlog=$sample
else
  die "no sample '$sample': expected one of $(cd rawlogs && ls ./*.rawlog | sed 's|^\./||; s|\.rawlog$||' | tr '\n' ' ')or a path to a .rawlog file"
fi
out=${2:-}
name=$(basename "$rawlog" .rawlog)
out=${out:-out/$name}
config=ini/freeinit.ini

[ -f "$rawlog" ] || die "input rawlog '$rawlog' not found"
[ -f "$config" ] || die "configuration '$config' not found"

BUILD_DIR=${BUILD_DIR:-build}
export BUILD_DIR
if [ "${SKIP_SETUP:-0}" != 1 ]; then
  echo "[demo] setup: installing missing packages and building into $BUILD_DIR (./scripts/setup.sh)"
  ./scripts/setup.sh || die "./scripts/setup.sh failed (see above)"
fi
app="$BUILD_DIR/bin/freeinit"
[ -x "$app" ] || die "$app was not built: is MRPT installed (libmrpt-dev) and FREEINIT_WITH_MRPT on?"

echo
echo "[demo] $app $config $rawlog --out $out"
echo
rc=0
"$app" "$config" "$rawlog" --out "$out" || rc=$?
echo
case $rc in
  0) ;;
  3) echo "[demo] the app ran but could not initialize (the reason is in $out/initial_state.ini)" ;;
  *) die "the app failed (exit code $rc): see its message above; nothing was written for it" ;;
esac

hr() { printf '%s\n' "------------------------------------------------------------------------"; }
hr
echo "$out/initial_state.ini (the 18x18 covariance line shortened to its diagonal's square roots):"
hr
awk '
  /^cov[ \t]*=/ {
    sub(/^cov[ \t]*=[ \t]*/, ""); n = split($0, c, /[ \t]+/)
    printf "cov       = <%d values, 18x18 row-major [dtheta p v b_g b_a g]>\n", n
    printf "  sigma dtheta [rad] %.3g %.3g %.3g\n", sqrt(c[1]), sqrt(c[20]), sqrt(c[39])
    names[1] = "p [m]"; names[2] = "v [m/s]"; names[3] = "b_g [rad/s]"
    names[4] = "b_a [m/s^2]"; names[5] = "g [m/s^2]"
    for (b = 1; b <= 5; ++b) {
      i = 3 * b
      printf "  sigma %-13s %.3g %.3g %.3g\n", names[b], sqrt(c[i*18+i+1]),
             sqrt(c[(i+1)*18+i+2]), sqrt(c[(i+2)*18+i+3])
    }
    next
  }
  { print }' "$out/initial_state.ini"

hr
if [ -f "$out/errors_wrt_gt.ini" ]; then
  echo "Errors w.r.t. the ground truth ($out/errors_wrt_gt.ini):"
  hr
  cat "$out/errors_wrt_gt.ini"
else
  echo "No ground-truth comparison (no ${rawlog%.rawlog}.truth.csv beside the rawlog, or not initialized)."
fi

hr
echo "Files written in $out:"
hr
find "$out" -maxdepth 1 -type f -printf '%f\t%s\n' | sort | while IFS=$'\t' read -r f size; do
  printf '  %-26s %10s bytes\n' "$f" "$size"
done
pngs=$(find "$out" -maxdepth 1 -name '*.png' | sort)
if [ -n "$pngs" ]; then
  echo
  echo "Snapshots (PNG):"
  for p in $pngs; do echo "  $(realpath "$p")"; done
fi
exit "$rc"
