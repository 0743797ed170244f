#!/usr/bin/env bash
# Discovery traffic per participant: how many bytes and packets N client participants cost when
# they join one telegrasp-server, and afterwards per second, on the wire (IP packets on `lo`).
#
# Run it in a network namespace of its own, where only this script's processes use `lo`:
#
#   unshare -n bash tests/bench/net/discovery_traffic.sh --build build --clients "1 8 32"
#
# For each profile (udp: unicast discovery to 127.0.0.1, participants find each other; wan: every
# participant a client of a local `fastdds discovery` server) and each N it starts the server
# (--empty-scene --tick-hz 1, so that its data, a SceneState and a ServerStatus a second per
# subscriber, stays small beside discovery), measures the loopback interface's byte and packet
# counters (/proc/net/dev) for 5 s (the baseline: the server, and the discovery server), then starts
# N telegrasp-echo clients at once (each a client participant as telegrasp-bot or a viewer has:
# 2 writers and readers of every output but ObjectGeometry, whose meshes, 3.6 MB of the 30
# stand-ins a join, are data rather than discovery: --topics all counts them too), waits until every one printed a ServerStatus (joined: discovered
# and matched), waits 5 s more, and then measures 10 s of steady state. Reported per N:
#   join: bytes and packets from the start of the clients to 5 s after the last joined, less the
#         baseline rate over that time; per participant = / N
#   steady: bytes/s and packets/s with the clients running, less the baseline; per participant
#           = / N (includes each client's 1 Hz SceneState and ServerStatus data and the
#           reliable writers' heartbeats: the cost of a participant that does nothing)
#   join time: start to the last client's first ServerStatus
#   ds cpu (wan): the discovery server's CPU time (utime + stime) during the join, and its share
#                 of one core during the steady window
set -euo pipefail

build=build
clients="1 8 32"
profiles="udp wan"
topics="HandSkeleton,GraspState,ContactSet,GraspEvent,SceneState,ServerStatus"
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --clients) clients="$2"; shift 2 ;;
    --profiles) profiles="$2"; shift 2 ;;
    --topics) topics="$2"; shift 2 ;;
    -h|--help) sed -n '2,25p' "$0"; exit 0 ;;
    *) echo "discovery_traffic.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done

server="$build/bin/telegrasp-server"
echo_bin="$build/bin/telegrasp-echo"
for b in "$server" "$echo_bin"; do
  [[ -x "$b" ]] || { echo "discovery_traffic.sh: $b is missing (build telegrasp-server and telegrasp-echo)" >&2; exit 1; }
done
if ip -o addr 2>/dev/null | grep -v ' lo ' | grep -q inet; then
  echo "discovery_traffic.sh: this network namespace has interfaces other than lo: run it under 'unshare -n'" >&2
  exit 1
fi
ip link set lo up

lo_counters() { awk -F'[: ]+' '$2 == "lo" { print $3, $4 }' /proc/net/dev; }
# utime + stime of a process in clock ticks (0 if there is none).
cpu_ticks() { [[ -n "$1" && -r /proc/$1/stat ]] && awk '{ sub(/^.*\) /, ""); print $12 + $13 }' /proc/$1/stat || echo 0; }
hz=$(getconf CLK_TCK)
now() { date +%s.%N; }
tmp=$(mktemp -d /tmp/telegrasp-discovery.XXXXXX)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$tmp"
}
trap cleanup EXIT

printf '%-8s %6s %10s %12s %10s %14s %12s %10s %12s %10s %12s %12s\n' profile N join_s join_bytes join_pkts \
  join_B/participant join_pkt/part steady_B/s steady_B/s/pt steady_pk/s ds_join_ms ds_steady_%
for profile in $profiles; do
  for n in $clients; do
    pids=()
    ds=""
    if [[ "$profile" == wan ]]; then
      # The server itself (`fastdds discovery` is a wrapper that would leave it behind when killed).
      fast-discovery-server -i 0 -l 127.0.0.1 -p 11811 > "$tmp/ds.log" 2>&1 &
      ds=$!
      pids+=($ds)
      sleep 1
    fi
    "$server" --domain 0 --profile "$profile" --empty-scene --tick-hz 1 > "$tmp/server.log" 2>&1 &
    pids+=($!)
    sleep 3
    read -r b_pre p_pre < <(lo_counters); t_pre=$(now)
    sleep 5
    read -r b0 p0 < <(lo_counters); t0=$(now); c0=$(cpu_ticks "$ds")
    for i in $(seq 1 "$n"); do
      if [[ "$topics" == all ]]; then topic_args=(); else topic_args=(--topics "$topics"); fi
      "$echo_bin" --domain 0 --profile "$profile" --duration-s 120 "${topic_args[@]}" > "$tmp/echo$i.out" 2> "$tmp/echo$i.err" &
      pids+=($!)
    done
    deadline=$(( $(date +%s) + 60 ))
    while :; do
      joined=0
      for i in $(seq 1 "$n"); do grep -q '"ServerStatus"' "$tmp/echo$i.out" 2>/dev/null && joined=$((joined + 1)); done
      [[ $joined -ge $n ]] && break
      if [[ $(date +%s) -gt $deadline ]]; then
        echo "discovery_traffic.sh: $profile N=$n: only $joined of $n clients joined within 60 s" >&2
        break
      fi
      sleep 0.1
    done
    t_joined=$(now)
    sleep 5
    read -r b1 p1 < <(lo_counters); t1=$(now); c1=$(cpu_ticks "$ds")
    sleep 10
    read -r b2 p2 < <(lo_counters); t2=$(now); c2=$(cpu_ticks "$ds")
    for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
    wait 2>/dev/null || true
    awk -v profile="$profile" -v n="$n" -v bpre="$b_pre" -v ppre="$p_pre" -v tpre="$t_pre" \
        -v b0="$b0" -v p0="$p0" -v t0="$t0" -v tj="$t_joined" -v b1="$b1" -v p1="$p1" -v t1="$t1" \
        -v b2="$b2" -v p2="$p2" -v t2="$t2" -v c0="$c0" -v c1="$c1" -v c2="$c2" -v hz="$hz" -v ds="$ds" 'BEGIN {
      base_b = (b0 - bpre) / (t0 - tpre); base_p = (p0 - ppre) / (t0 - tpre)
      jb = (b1 - b0) - base_b * (t1 - t0); jp = (p1 - p0) - base_p * (t1 - t0)
      sb = (b2 - b1) / (t2 - t1) - base_b; sp = (p2 - p1) / (t2 - t1) - base_p
      dsj = ds == "" ? "-" : sprintf("%.0f", (c1 - c0) * 1000 / hz)
      dss = ds == "" ? "-" : sprintf("%.2f", (c2 - c1) / hz / (t2 - t1) * 100)
      printf "%-8s %6d %10.2f %12.0f %10.0f %14.0f %12.1f %10.0f %12.0f %10.1f %12s %12s\n", profile, n, tj - t0, jb, jp,
        jb / n, jp / n, sb, sb / n, sp, dsj, dss
      printf "         (baseline without clients: %.0f B/s, %.1f packets/s)\n", base_b, base_p
    }'
  done
done
