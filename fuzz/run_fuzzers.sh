#!/usr/bin/env bash
# Builds the fuzz harnesses with clang (libFuzzer + ASan + UBSan) and runs them.
#   fuzz/run_fuzzers.sh [seconds] [harness...]
# seconds: per harness (default 60); harnesses: names of fuzz/fuzz_<name>.cpp (default: all of
# them, one after the other). Each runs on a working corpus in the build folder, seeded from
# fuzz/corpus/<name>/ (the committed seeds are never modified); crashes, leaks, timeouts and
# out-of-memory inputs are written to <build>/artifacts/<name>/ and stop that harness.
# Environment: FUZZ_BUILD_DIR (default build-fuzz), JOBS (build, default 2), FUZZ_RSS_MB (per
# harness, default 2048), FUZZ_TIMEOUT (seconds per input, default 10), FUZZ_ARGS (more libFuzzer
# flags). Prints, per harness: executions, coverage (cov, ft), corpus size, and the verdict.
# To minimize the working corpus into the committed seeds: the fuzzer's -merge=1 (see README).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
seconds=${1:-60}
[ $# -gt 0 ] && shift
if ! [[ $seconds =~ ^[0-9]+$ ]] || [ "$seconds" -eq 0 ]; then
  echo "run_fuzzers.sh: seconds must be a positive whole number, not '$seconds'" >&2
  exit 2
fi
all=()
for f in "$here"/fuzz_*.cpp; do
  n=$(basename "$f" .cpp)
  all+=("${n#fuzz_}")
done
harnesses=("$@")
[ ${#harnesses[@]} -eq 0 ] && harnesses=("${all[@]}")
for h in "${harnesses[@]}"; do
  [ -f "$here/fuzz_$h.cpp" ] || { echo "run_fuzzers.sh: no harness '$h' (have: ${all[*]})" >&2; exit 2; }
done

build=${FUZZ_BUILD_DIR:-$root/build-fuzz}
command -v clang++ > /dev/null || { echo "run_fuzzers.sh: clang++ not found (apt-get install clang libclang-rt-14-dev)" >&2; exit 2; }
CXX=clang++ cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo > /dev/null
targets=()
for h in "${harnesses[@]}"; do targets+=("fuzz_$h"); done
cmake --build "$build" -j"${JOBS:-2}" --target "${targets[@]}"

status=0
summary=()
for h in "${harnesses[@]}"; do
  work="$build/corpus/$h"
  artifacts="$build/artifacts/$h"
  mkdir -p "$work" "$artifacts"
  log="$build/fuzz_$h.log"
  echo "== $h: ${seconds} s (log: $log)"
  set +e
  # The bag and MCAP harnesses write each input to a file: the working folder must be writable,
  # and the temporary folder is in memory where there is one (several times the executions).
  tmp=${TMPDIR:-/tmp}
  [ -z "${TMPDIR:-}" ] && [ -d /dev/shm ] && [ -w /dev/shm ] && tmp=/dev/shm
  (cd "$build" && TMPDIR=$tmp ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1} \
     "./fuzz_$h" -max_total_time="$seconds" -rss_limit_mb="${FUZZ_RSS_MB:-2048}" \
     -timeout="${FUZZ_TIMEOUT:-10}" -print_final_stats=1 -artifact_prefix="$artifacts/" \
     ${FUZZ_ARGS:-} "$work" "$here/corpus/$h") > "$log" 2>&1
  rc=$?
  set -e
  last=$(grep -E '^#[0-9]+' "$log" | tail -1)
  execs=$(grep -E '^stat::number_of_executed_units' "$log" | awk '{print $2}')
  files=$(find "$work" -type f | wc -l)
  bytes=$(du -sb "$work" | awk '{print $1}')
  verdict="clean"
  if [ $rc -ne 0 ]; then
    verdict="FINDING (exit $rc): $(ls "$artifacts" | tr '\n' ' ')"
    status=1
  fi
  line="$h: ${seconds} s, ${execs:-?} executions, $(echo "$last" | grep -oE 'cov: [0-9]+ ft: [0-9]+'), corpus $files files / $bytes bytes: $verdict"
  echo "$line"
  summary+=("$line")
done
echo
echo "Summary:"
printf '  %s\n' "${summary[@]}"
exit $status
