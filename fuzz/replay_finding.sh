#!/bin/sh
# Runs one input under an address-space limit and a time limit, and checks how it ends.
#   replay_finding.sh measure OUT -- CMD...
#       the smallest `ulimit -v` (KB, to 4 MB) under which CMD exits 0, written to OUT
#   replay_finding.sh import BASE FILE IMPORTER INI
#       IMPORTER FILE -c INI must exit 1 with exactly one line on stderr,
#       "<importer>: error: FILE: ...", and leave no rawlog
#   replay_finding.sh replay BASE FILE DRIVER
#       DRIVER FILE must exit 0 with exactly one line, "FILE: ok: ..." or "FILE: error: ..."
#   replay_finding.sh rawlog BASE FILE APP INI
#       APP INI FILE (freeinit) must exit 1 with exactly one line on stderr,
#       "<app>: error: FILE: ...", and leave no output folder
#   replay_finding.sh ini BASE FILE APP RAWLOG
#       APP FILE RAWLOG (freeinit) the same, the line naming the INI file
# The limit of import and replay is BASE's figure + 300 MB; the time limit 20 s. Exit 77 (ctest:
# skipped) when FILE is absent.
set -u
EXTRA_KB=$((300 * 1024))
SECONDS_LIMIT=20
mode=$1
shift
case $mode in
measure)
  out=$1
  shift 2  # OUT --
  lo=0
  hi=$((16 * 1024 * 1024))
  if ! (ulimit -v $hi; "$@") > /dev/null 2>&1; then
    echo "the valid input fails even with ulimit -v $hi: $*" >&2
    exit 1
  fi
  while [ $((hi - lo)) -gt 4096 ]; do
    mid=$(((lo + hi) / 2))
    if (ulimit -v $mid; "$@") > /dev/null 2>&1; then hi=$mid; else lo=$mid; fi
  done
  echo $hi > "$out"
  echo "a valid input runs within ulimit -v $hi KB: $*"
  ;;
import | replay | rawlog | ini)
  base=$1 file=$2 tool=$3
  [ -f "$file" ] || { echo "skipped: $file is not here"; exit 77; }
  limit=$(($(cat "$base") + EXTRA_KB))
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' EXIT
  start=$(date +%s)
  if [ "$mode" = import ]; then
    # The message is on stderr (stdout has the progress lines).
    (ulimit -v $limit; exec timeout $SECONDS_LIMIT "$tool" "$file" -c "$4" -q -o "$tmp/out.rawlog") \
      > "$tmp/other" 2> "$tmp/line"
  elif [ "$mode" = rawlog ]; then
    (ulimit -v $limit; exec timeout $SECONDS_LIMIT "$tool" "$4" "$file" -q --out "$tmp/out") \
      > "$tmp/other" 2> "$tmp/line"
  elif [ "$mode" = ini ]; then
    (ulimit -v $limit; exec timeout $SECONDS_LIMIT "$tool" "$file" "$4" -q --out "$tmp/out") \
      > "$tmp/other" 2> "$tmp/line"
  else
    (ulimit -v $limit; exec timeout $SECONDS_LIMIT "$tool" "$file") > "$tmp/line" 2> "$tmp/other"
  fi
  rc=$?
  elapsed=$(($(date +%s) - start))
  echo "exit $rc after ${elapsed} s within ulimit -v $limit KB:"
  cat "$tmp/line"
  lines=$(wc -l < "$tmp/line")
  name=$(basename "$tool")
  if [ "$mode" = import ]; then
    [ $rc -eq 1 ] || { echo "FAIL: exit code $rc, expected 1"; exit 1; }
    [ ! -e "$tmp/out.rawlog" ] && [ ! -e "$tmp/out.rawlog.tmp" ] || { echo "FAIL: a rawlog was left"; exit 1; }
    expect="$name: error: $file: "
  elif [ "$mode" = rawlog ] || [ "$mode" = ini ]; then
    [ $rc -eq 1 ] || { echo "FAIL: exit code $rc, expected 1"; exit 1; }
    [ ! -e "$tmp/out" ] || { echo "FAIL: an output folder was left"; exit 1; }
    expect="$name: error: $file"
  else
    [ $rc -eq 0 ] || { echo "FAIL: exit code $rc, expected 0"; cat "$tmp/other"; exit 1; }
    expect="$file: "
  fi
  [ "$lines" -eq 1 ] || { echo "FAIL: $lines lines, expected one"; exit 1; }
  case $(cat "$tmp/line") in
  "$expect"*) ;;
  *) echo "FAIL: the line does not start with '$expect'"; exit 1 ;;
  esac
  echo "PASS"
  ;;
*)
  echo "usage: $0 measure OUT -- CMD... | import BASE FILE IMPORTER INI | replay BASE FILE DRIVER | rawlog BASE FILE APP INI | ini BASE FILE APP RAWLOG" >&2
  exit 2
  ;;
esac
