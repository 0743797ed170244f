#!/usr/bin/env bash
# The main job: installs dependencies, builds the tools (the build's output goes to a log file
# whose path is printed), starts telegrasp-server in the background on a private DDS domain with
# the loopback profile, and lets a bot with two hands grasp every object of the scene once over
# DDS; prints the bot's per-object table, stops the server (SIGTERM), prints its log and where to
# look next, and exits with the bot's status (0: every trial done, held or not, as the table shows;
# 1 the build or the server failed; 130 interrupted).
# telegrasp-view runs beside them: open the URL it prints (http://localhost:8765/) to watch the
# grasps in the browser, or connect Foxglove / Lichtblick to ws://localhost:8765.
#
#   deploy/run-demo.sh [--objects DIR] [--domain N] [--trials N] [--skill NAME] [--view-seconds N]
#
#   --objects DIR   the scene: every mesh file in DIR (default: the 30 built-in stand-ins);
#                   server and bot both load it (the bot to plan its grasps)
#   --domain N      DDS domain, so the demo never meets other DDS traffic (default 42)
#   --trials N      grasps per object (default 1); --skill perfect|experienced|inexperienced
#   --view-seconds N  keep the server and the view up N seconds after the bot is done (default 0)
#
# TELEGRASP_BUILD_DIR picks the build folder (default build). The in-process evaluation, with no
# network, is deploy/run-eval.sh.
set -euo pipefail

objects=()
domain=42
bot_args=(--trials 1)
view_seconds=0
while [ $# -gt 0 ]; do
  case "$1" in
    --objects|--domain|--trials|--skill|--view-seconds)
      [ $# -ge 2 ] || { echo "run-demo: $1 needs a value" >&2; exit 2; } ;;&
    --objects) objects=(--objects "$(realpath -m -- "$2")"); shift 2 ;;
    --domain) domain="$2"; shift 2 ;;
    --trials|--skill) bot_args+=("$1" "$2"); shift 2 ;;
    --view-seconds) view_seconds="$2"; shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "run-demo: unknown option '$1' (see deploy/run-demo.sh --help)" >&2; exit 2 ;;
  esac
done
[[ "$view_seconds" =~ ^[0-9]+$ ]] || { echo "run-demo: --view-seconds expects whole seconds, got '$view_seconds'" >&2; exit 2; }

cd "$(dirname "$0")/.."
build="${TELEGRASP_BUILD_DIR:-build}"
deploy/install-deps.sh
# The build's output goes to a log, not between the results; only its end is shown if it fails.
mkdir -p "$build"
build_log="$(cd "$build" && pwd)/run-demo-build.log"
echo "run-demo: building telegrasp-server, -bot, -view, -eval and -echo (log: $build_log) ..." >&2
build_start=$SECONDS
if ! { cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo &&
       cmake --build "$build" -j"$(nproc)" --target telegrasp-server telegrasp-bot telegrasp-view telegrasp-eval telegrasp-echo; } >"$build_log" 2>&1; then
  echo "run-demo: the build failed; the end of $build_log:" >&2
  tail -n 30 "$build_log" | sed 's/^/  /' >&2
  exit 1
fi
echo "run-demo: built in $((SECONDS - build_start)) s" >&2

server_log="$(mktemp -t telegrasp-demo-server.XXXXXX)"
server_pid=""
bot_pid=""
view_pid=""
view_log="$(mktemp -t telegrasp-demo-view.XXXXXX)"
cleanup() {
  trap - EXIT INT TERM
  [ -n "$view_pid" ] && kill -TERM "$view_pid" 2>/dev/null && wait "$view_pid" 2>/dev/null
  rm -f "$view_log"
  [ -n "$bot_pid" ] && kill -TERM "$bot_pid" 2>/dev/null && wait "$bot_pid" 2>/dev/null
  if [ -n "$server_pid" ]; then
    kill -TERM "$server_pid" 2>/dev/null
    wait "$server_pid" 2>/dev/null
    sed 's/^/  /' "$server_log" >&2
  fi
  rm -f "$server_log"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

echo "run-demo: telegrasp-server on DDS domain $domain (loopback profile); its log follows the table" >&2
"$build/bin/telegrasp-server" --domain "$domain" --profile loopback "${objects[@]}" >"$server_log" 2>&1 &
server_pid=$!

# The browser view of the same scene; the demo goes on without it if it cannot start.
"$build/bin/telegrasp-view" --domain "$domain" --profile loopback --port 8765 >"$view_log" 2>&1 &
view_pid=$!
for _ in $(seq 50); do grep -q "http://" "$view_log" && break; kill -0 "$view_pid" 2>/dev/null || break; sleep 0.1; done
if grep -q "http://" "$view_log"; then
  echo "run-demo: watch it at http://localhost:8765/ (Foxglove or Lichtblick: open a Foxglove WebSocket connection to ws://localhost:8765)" >&2
else
  echo "run-demo: telegrasp-view did not start; going on without it:" >&2
  sed 's/^/  /' "$view_log" >&2
fi

start=$SECONDS
"$build/bin/telegrasp-bot" --domain "$domain" --profile loopback --hands both --timeout-s 60 \
  "${bot_args[@]}" "${objects[@]}" &
bot_pid=$!
set +e
wait -n -p finished "$server_pid" "$bot_pid"
status=$?
set -e
if [ "$finished" = "$server_pid" ]; then
  server_pid=""
  echo "run-demo: telegrasp-server exited (status $status) before the bot was done:" >&2
  sed 's/^/  /' "$server_log" >&2
  exit 1
fi
bot_pid=""
echo "run-demo: bot finished with status $status in $((SECONDS - start)) s" >&2
if [ "$status" = 5 ]; then  # every trial done, some object not held: the table above says which
  echo "run-demo: every trial done; not every object was held (see the table and the bot's last line)" >&2
  status=0
fi
if [ "$view_seconds" -gt 0 ] && kill -0 "$view_pid" 2>/dev/null; then
  echo "run-demo: the view stays up for $view_seconds s at http://localhost:8765/" >&2
  sleep "$view_seconds"
fi
cleanup || true  # stops the server and prints its log, before the pointers below
cat >&2 <<NEXT

run-demo: where to look next
  the grasps in the browser: deploy/run-demo.sh --view-seconds 300, then open http://localhost:8765/
  the paper's experiment through servers over DDS, with an HTML report (about 30 s):
    $build/bin/telegrasp-eval protocol --mode both --json run.json --csv run.csv --report run.html
  a server's outputs as JSON lines, one per sample, while a bot drives it:
    $build/bin/telegrasp-server --domain $domain & $build/bin/telegrasp-bot --domain $domain --hands both &
    $build/bin/telegrasp-echo --domain $domain --topics GraspEvent
  the same grasps in-process, no network: deploy/run-eval.sh; every tool explains itself with --help
NEXT
exit "$status"
