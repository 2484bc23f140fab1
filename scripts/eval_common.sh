# Shared by the evaluation scripts (sourced, not run): their one option, their output and
# scratch folders, the evaluation program and the copy of a table between a file's markers. The
# caller sets `tag` (its messages' prefix) before sourcing and runs from the repository's root.

# --no-readme (readme=0: write the files only) or nothing (readme=1).
readme=1
case "${1:-}" in
  "") ;;
  --no-readme) readme=0 ;;
  *) echo "[$tag] error: unknown option $1 (usage: $0 [--no-readme])" >&2; exit 2 ;;
esac

# The tables and runs go to out; tmp is removed on exit.
out=gui_snapshots
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# The Release build's freeinit-eval (BUILD_DIR, default build).
eval_app=${BUILD_DIR:-build}/bin/freeinit-eval
[ -f "$eval_app" ] && [ -x "$eval_app" ] || { echo "[$tag] error: $eval_app not built" >&2; exit 1; }

# copy_between_markers FILE NAME TARGET: replaces what TARGET holds between the lines
# "<!-- NAME:begin -->" and "<!-- NAME:end -->" with FILE; returns 1 (TARGET unchanged) when
# TARGET lacks either marker.
copy_between_markers() {
  local file=$1 name=$2 target=$3
  grep -q "^<!-- $name:begin -->$" "$target" && grep -q "^<!-- $name:end -->$" "$target" ||
    return 1
  awk -v file="$file" -v name="$name" '
    $0 == "<!-- " name ":begin -->" { print; while ((getline line < file) > 0) print line; skip = 1; next }
    $0 == "<!-- " name ":end -->" { skip = 0 }
    !skip' "$target" > "$target.tmp"
  mv "$target.tmp" "$target"
}
