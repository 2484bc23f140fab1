#!/usr/bin/env bash
# Checks that every tracked C++ file is formatted as .clang-format says (clang-format-14, the
# version Debian bookworm ships: another version may format differently). Prints one line per
# file that is not, and exits 1 if there is any.
set -euo pipefail
cd "$(dirname "$0")/.."
CLANG_FORMAT=${CLANG_FORMAT:-clang-format-14}
if ! command -v "$CLANG_FORMAT" >/dev/null; then
  echo "check_format: $CLANG_FORMAT not found (apt-get install clang-format-14)" >&2
  exit 2
fi
bad=()
while IFS= read -r f; do
  "$CLANG_FORMAT" --dry-run --Werror "$f" >/dev/null 2>&1 || bad+=("$f")
done < <(git ls-files '*.cpp' '*.h')
for f in ${bad[@]+"${bad[@]}"}; do
  echo "check_format: not formatted: $f"
done
if [ ${#bad[@]} -gt 0 ]; then
  echo "check_format: ${#bad[@]} file(s); fix with: $CLANG_FORMAT -i <file>...  (see the diff first: $CLANG_FORMAT <file> | diff <file> -)"
  exit 1
fi
echo "check_format: all $(git ls-files '*.cpp' '*.h' | wc -l) files formatted"
