#!/usr/bin/env bash
# `cmake --install` into a fresh prefix, which is then moved: the apps run from <prefix>/bin with
# their libraries found relative to themselves (not in the build tree), `freeinit --plugin-path`
# prints the installed plugin, stock rawlog-edit loads it and reads every object of a sample, and
# `freeinit <input.rawlog>` writes a new output folder with the defaults.
#   install_prefix.sh <source dir> <build dir>
set -euo pipefail
src=$1
build=$2
tmp=$(mktemp -d "${TMPDIR:-/tmp}/freeinit_install.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

cmake --install "$build" --prefix "$tmp/prefix" > "$tmp/install.log"
mv "$tmp/prefix" "$tmp/moved"
p=$tmp/moved
for app in freeinit freeinit-sim freeinit-online freeinit-stream freeinit-icp-slam \
           freeinit-eval freeinit-eval-rawlog; do
  [ -x "$p/bin/$app" ] || fail "$p/bin/$app not installed"
done
[ -f "$p/share/freeinit/ini/freeinit.ini" ] || fail "ini/freeinit.ini not installed"

plugin=$("$p/bin/freeinit" --plugin-path)
case "$plugin" in
  "$p"/*/freeinit/libfreeinit_mrpt_plugins.so) ;;
  *) fail "freeinit --plugin-path printed '$plugin', not the plugin in $p" ;;
esac
[ -f "$plugin" ] || fail "$plugin does not exist"
! ldd "$p/bin/freeinit" "$plugin" | grep "not found" || fail "a library is not found"
! ldd "$p/bin/freeinit" | grep -F "$(cd "$build" && pwd)" || fail "the installed app uses the build tree"

rawlog-edit -p "$plugin" --info -i "$src/rawlogs/dyna_01.rawlog" > "$tmp/info.txt" 2>&1
grep -Eq "Overall number of objects *: 316" "$tmp/info.txt" ||
  fail "rawlog-edit -p $plugin did not read every object: $(cat "$tmp/info.txt")"

cd "$tmp"
"$p/bin/freeinit" -q "$src/rawlogs/stat_01.rawlog" > run.txt || fail "$(cat run.txt)"
state=$(ls freeinit_out/stat_01.*/initial_state.ini)
grep -q "^status *= *ok" "$state" || fail "$state: $(cat "$state")"
echo "install-ok: $plugin"
