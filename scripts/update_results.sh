#!/usr/bin/env bash
# Re-measures the README's Results: runs freeinit-eval over every preset x 3 seeds (the exact
# command the README gives), writes gui_snapshots/eval_presets.{md,csv} and the figures, and puts
# the new summary table into README.md between its results-table markers.
#
#   ./scripts/update_results.sh
#
# Environment: BUILD_DIR (default build; must hold a Release build of freeinit-eval).
set -euo pipefail
cd "$(dirname "$0")/.."
eval_app=${BUILD_DIR:-build}/apps/freeinit-eval
[ -x "$eval_app" ] || { echo "[results] error: $eval_app not built" >&2; exit 1; }

taskset -c 0 "$eval_app" --jobs 1 --seeds 3 --md gui_snapshots/eval_presets.md \
  --csv gui_snapshots/eval_presets.csv --plots gui_snapshots > /dev/null

# The summary is the first table of the report; the README holds it between the markers.
table=$(awk '/^\| metric \| method \|/ {on = 1} on && !/^\|/ {exit} on' gui_snapshots/eval_presets.md)
[ -n "$table" ] || { echo "[results] error: no summary table in eval_presets.md" >&2; exit 1; }
grep -q '^<!-- results-table:begin -->$' README.md && grep -q '^<!-- results-table:end -->$' README.md \
  || { echo "[results] error: README.md lacks the results-table markers" >&2; exit 1; }
tmp=README.md.tmp
awk -v table="$table" '
  /^<!-- results-table:begin -->$/ { print; print table; skip = 1; next }
  /^<!-- results-table:end -->$/ { skip = 0 }
  !skip' README.md > "$tmp"
mv "$tmp" README.md
echo "[results] README.md table, gui_snapshots/eval_presets.{md,csv} and the figures updated;" \
  "check the prose around the table against the new numbers"
