#!/usr/bin/env bash
# Installs the build into a scratch prefix and uses it as a new user would: from /, with no
# TELEGRASP_* variable set and, when run as root, with the source and build trees hidden under
# empty mounts (unshare -m), the installed server serves two objects and the installed bot grasps
# them over loopback DDS; telegrasp-eval finds its rig and report data. Also checks that no
# installed file names the source or build tree.
# Usage: telegrasp-test-domains installed_prefix_test.sh BUILD_DIR SOURCE_DIR
#    or: installed_prefix_test.sh BUILD_DIR SOURCE_DIR DOMAIN
# The DDS domain is the one telegrasp-test-domains leased (TELEGRASP_TEST_DOMAIN), held by this
# script and every process it starts, so no concurrent test run uses it.
set -euo pipefail
build_dir=$(realpath "$1")
source_dir=$(realpath "$2")
domain=${3:-${TELEGRASP_TEST_DOMAIN:-}}
[ -n "$domain" ] || { echo "installed_prefix_test.sh: no DDS domain: run it under telegrasp-test-domains or pass DOMAIN" >&2; exit 2; }
work=$(mktemp -d /tmp/telegrasp-installed.XXXXXX)
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix

step() { echo "== $*"; }
fail() { echo "FAIL: $*" >&2; exit 1; }

step "install (stripped) into $prefix"
cmake --install "$build_dir" --prefix "$prefix" --strip >"$work/install.log"
for f in bin/telegrasp-server bin/telegrasp-bot bin/telegrasp-echo bin/telegrasp-eval bin/telegrasp-replay \
         share/telegrasp/telegrasp_profiles.xml share/telegrasp/rigs/human_right.textproto \
         share/telegrasp/rigs/human_left.textproto share/telegrasp/rigs/gripper3.textproto \
         share/telegrasp/rigs/human_right_opposable.textproto share/telegrasp/rigs/human_left_opposable.textproto \
         share/telegrasp/paper_results_per_object.csv; do
  [ -e "$prefix/$f" ] || fail "$f was not installed"
done

step "no installed file names the source tree ($source_dir) or the build tree ($build_dir)"
if grep -rlF -e "$source_dir" -e "$build_dir" "$prefix"; then
  fail "the files above name the source or build tree"
fi

# The scenario, run from / with a clean environment.
cat >"$work/server.textproto" <<CONF
domain: $domain
profile: "loopback"
objects { model: "004_sugar_box" x: 0.45 y: -0.1 }
objects { model: "055_baseball" x: 0.45 y: 0.15 }
CONF
cat >"$work/scenario.sh" <<SCENARIO
set -euo pipefail
cd /
P=$prefix
\$P/bin/telegrasp-server --config $work/server.textproto >$work/server.log 2>&1 &
server=\$!
trap 'kill \$server 2>/dev/null || true' EXIT
# Exit status 5: every trial done, some not held (the records are checked below).
\$P/bin/telegrasp-bot --domain $domain --trials 1 --timeout-s 30 --json $work/bot.json >$work/bot.out 2>$work/bot.err ||
  [ \$? -eq 5 ]
kill -INT \$server
wait \$server
\$P/bin/telegrasp-eval run --trials 1 --objects $work/objects --json $work/eval.json >$work/eval.out 2>$work/eval.err
SCENARIO
mkdir -p "$work/objects"
# One small mesh for the eval: a 6 cm cube as ASCII STL (12 triangles).
{
  echo "solid cube"
  v=("-0.03 -0.03 -0.03" "-0.03 -0.03 0.03" "-0.03 0.03 -0.03" "-0.03 0.03 0.03"
     "0.03 -0.03 -0.03" "0.03 -0.03 0.03" "0.03 0.03 -0.03" "0.03 0.03 0.03")
  for f in "0 1 3" "0 3 2" "4 6 7" "4 7 5" "0 4 5" "0 5 1" "2 3 7" "2 7 6" "0 2 6" "0 6 4" "1 5 7" "1 7 3"; do
    echo " facet normal 0 0 0"; echo "  outer loop"
    for i in $f; do echo "   vertex ${v[$i]}"; done
    echo "  endloop"; echo " endfacet"
  done
  echo "endsolid cube"
} >"$work/objects/cube.stl"

hide=""
if [ "$(id -u)" -eq 0 ] && command -v unshare >/dev/null && unshare -m true 2>/dev/null; then
  hide="mount -t tmpfs none $source_dir;"
  case "$build_dir/" in "$source_dir"/*) ;; *) hide="$hide mount -t tmpfs none $build_dir;" ;; esac
  step "run from / with the source and build trees hidden (unshare -m)"
  unshare -m bash -c "$hide [ ! -e $source_dir/CMakeLists.txt ] || exit 3; exec env -i PATH=/usr/bin:/bin HOME=/ bash $work/scenario.sh"
else
  step "run from / (not root: the source and build trees stay visible, the environment is clean)"
  env -i PATH=/usr/bin:/bin HOME=/ bash "$work/scenario.sh"
fi

step "the bot grasped both objects"
cat "$work/bot.out"
held=$(grep -c '"held_after_lift": true' "$work/bot.json" || true)
[ "$held" -ge 2 ] || fail "the bot held $held of 2 objects"
step "telegrasp-eval ran on the installed rig"
grep -q '"held_after_lift"' "$work/eval.json" || fail "telegrasp-eval wrote no records ($(tail -3 "$work/eval.err"))"
step "the systemd unit: ExecStart names the installed server and its configuration parses"
unit=$source_dir/deploy/telegrasp-server.service
exec_start=$(sed -n 's/^ExecStart=//p' "$unit")
read -r exe flag config <<<"$exec_start"
[ "$exe" = /usr/local/bin/telegrasp-server ] || fail "$unit: ExecStart runs '$exe', not the default prefix's /usr/local/bin/telegrasp-server"
[ "$flag" = --config ] || fail "$unit: ExecStart passes '$flag', expected --config FILE"
grep -q "^Environment=TELEGRASP" "$unit" && fail "$unit: the installed server needs no TELEGRASP_* variable"
# The unit's own install notes copy deploy/server.example.textproto to $config.
(cd / && env -i PATH=/usr/bin:/bin "$prefix/bin/telegrasp-server" --config "$source_dir/deploy/server.example.textproto" \
    --list-models >"$work/models.txt") || fail "telegrasp-server rejects deploy/server.example.textproto"
grep -q '^profile: *"loopback"' "$source_dir/deploy/server.example.textproto" &&
  fail "deploy/server.example.textproto uses the loopback profile, which the unit advises against"
if command -v systemd-analyze >/dev/null; then
  sed "s|/usr/local/bin/|$prefix/bin/|" "$unit" >"$work/telegrasp-server.service"
  systemd-analyze verify "$work/telegrasp-server.service" || fail "systemd-analyze verify $unit"
else
  echo "(systemd-analyze not installed: unit syntax not verified)"
fi
echo "PASS"
