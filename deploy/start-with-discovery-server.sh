#!/usr/bin/env bash
# Starts a Fast DDS discovery server and a telegrasp server that finds its clients through it
# (the `wan` profile of deploy/fastdds/telegrasp_profiles.xml), for clients on other networks or
# wherever multicast discovery does not reach.
#
#   deploy/start-with-discovery-server.sh [--ip IP] [--port PORT] [--] [telegrasp-server options]
#
#   --ip IP       address the discovery server listens on, and clients reach it at (default 127.0.0.1;
#                 use the machine's public or LAN address for remote clients)
#   --port PORT   its UDP port (default 11811)
#   anything else goes to telegrasp-server (e.g. --domain 3 --objects DIR --config FILE)
#
# It runs `fastdds discovery -i 0 -l IP -p PORT` (from fastdds-tools; started as the binary that
# command launches, fast-discovery-server, so that it can be stopped and reaped), waits until it
# listens, then runs build/bin/telegrasp-server (or telegrasp-server from PATH) with `--profile wan
# --discovery-server IP:PORT`. Clients use `--profile wan --discovery-server IP:PORT` too (or
# TELEGRASP_DISCOVERY_SERVERS=IP:PORT). For two redundant discovery servers and many scenes, see
# the units in deploy/systemd/ and the README. Ctrl-C, or the telegrasp server exiting, stops both;
# the exit status is the telegrasp server's.
#
# Example: server and a bot on one machine, through the discovery server:
#   deploy/start-with-discovery-server.sh --domain 7 &
#   build/bin/telegrasp-bot --profile wan --discovery-server 127.0.0.1:11811 --domain 7 --trials 1
set -euo pipefail

here="$(cd "$(dirname "$0")" && pwd)"
repo="$(dirname "$here")"
ip=127.0.0.1
port=11811
server_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --ip) [ $# -ge 2 ] || { echo "start-with-discovery-server: --ip needs a value" >&2; exit 2; }; ip="$2"; shift 2 ;;
    --port) [ $# -ge 2 ] || { echo "start-with-discovery-server: --port needs a value" >&2; exit 2; }; port="$2"; shift 2 ;;
    --) shift; server_args+=("$@"); break ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) server_args+=("$1"); shift ;;
  esac
done
[[ "$port" =~ ^[0-9]+$ ]] && [ "$port" -ge 1 ] && [ "$port" -le 65535 ] ||
  { echo "start-with-discovery-server: --port expects 1..65535, got '$port'" >&2; exit 2; }
[[ "$ip" =~ ^[0-9]{1,3}(\.[0-9]{1,3}){3}$ ]] ||
  { echo "start-with-discovery-server: --ip expects an IPv4 address, got '$ip'" >&2; exit 2; }

if [ -x "$repo/build/bin/telegrasp-server" ]; then
  server="$repo/build/bin/telegrasp-server"
elif command -v telegrasp-server >/dev/null; then
  server="$(command -v telegrasp-server)"
else
  echo "start-with-discovery-server: no telegrasp-server in $repo/build/bin or on PATH (build it first)" >&2
  exit 1
fi
command -v fast-discovery-server >/dev/null ||
  { echo "start-with-discovery-server: 'fast-discovery-server' not found (apt-get install fastdds-tools)" >&2; exit 1; }

discovery_pid=""
server_pid=""
cleanup() {
  trap - EXIT INT TERM
  [ -n "$server_pid" ] && kill -TERM "$server_pid" 2>/dev/null && wait "$server_pid" 2>/dev/null || true
  [ -n "$discovery_pid" ] && kill -TERM "$discovery_pid" 2>/dev/null && wait "$discovery_pid" 2>/dev/null || true
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# The discovery server (`fastdds discovery -i 0 -l IP -p PORT` without the Python launcher).
log="$(mktemp -t telegrasp-discovery.XXXXXX)"
fast-discovery-server -i 0 -l "$ip" -p "$port" >"$log" 2>&1 &
discovery_pid=$!
listening=""
for _ in $(seq 1 100); do  # up to 10 s
  kill -0 "$discovery_pid" 2>/dev/null || break
  if ss -Hulnp 2>/dev/null | grep -q ":$port .*pid=$discovery_pid,"; then listening=1; break; fi
  sleep 0.1
done
if [ -z "$listening" ]; then
  echo "start-with-discovery-server: the discovery server did not start listening on $ip:$port:" >&2
  cat "$log" >&2
  rm -f "$log"
  exit 1
fi
rm -f "$log"
echo "start-with-discovery-server: Fast DDS discovery server listening on $ip:$port (pid $discovery_pid)" >&2

"$server" --profile wan --discovery-server "$ip:$port" "${server_args[@]}" &
server_pid=$!
set +e
wait "$server_pid"  # Ctrl-C / SIGTERM run the trap instead: exit 130, stopping both
status=$?
server_pid=""
exit "$status"
