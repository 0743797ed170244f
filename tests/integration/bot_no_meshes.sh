#!/usr/bin/env bash
# The bot with no mesh files against a free-running server (real time, 90 Hz, not --lockstep) over
# loopback DDS: issue 12 section 6's target run. Prints the held count of every object and the
# total, and exits non-zero if any object is below the target share.
#
#   tests/integration/bot_no_meshes.sh [--build DIR] [--objects DIR] [--seeds "1 2"] [--trials N]
#                                      [--target PERCENT] [--out DIR]
#
# --objects DIR: the server's meshes (default: none, the 30 built-in stand-ins); the bot never
# gets them. Each seed is one server and one bot run on a DDS domain leased with
# telegrasp-test-domains. Logs and JSON records go to --out (default a new folder in $TMPDIR).
set -euo pipefail
cd "$(dirname "$0")/../.."
build=build objects="" seeds="1" trials=3 target=95 out=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --objects) objects="$2"; shift 2 ;;
    --seeds) seeds="$2"; shift 2 ;;
    --trials) trials="$2"; shift 2 ;;
    --target) target="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    -h|--help) sed -n '2,11p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "bot_no_meshes.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done
[[ -n "$out" ]] || out=$(mktemp -d "${TMPDIR:-/tmp}/telegrasp_bot_no_meshes.XXXXXX")
mkdir -p "$out"
bin="$build/bin"
for tool in telegrasp-server telegrasp-bot telegrasp-test-domains; do
  [[ -x "$bin/$tool" ]] || { echo "bot_no_meshes.sh: $bin/$tool not built" >&2; exit 1; }
done

# One seed: a server and a bot on a leased domain (TELEGRASP_TEST_DOMAIN), inside the lease.
run_one() {
  local seed="$1" domain="$TELEGRASP_TEST_DOMAIN"
  local server_args=(--domain "$domain" --profile loopback)
  [[ -n "$objects" ]] && server_args+=(--objects "$objects")
  "$bin/telegrasp-server" "${server_args[@]}" >"$out/server_seed$seed.log" 2>&1 &
  local server=$!
  local status=0
  "$bin/telegrasp-bot" --domain "$domain" --profile loopback --skill experienced --trials "$trials" \
    --seed "$seed" --json "$out/bot_seed$seed.json" --timeout-s 30 >"$out/bot_seed$seed.out" 2>"$out/bot_seed$seed.log" ||
    status=$?
  kill -TERM "$server" 2>/dev/null || true
  wait "$server" 2>/dev/null || true
  echo "seed $seed: telegrasp-bot exit status $status ($(grep -o '^held .*' "$out/bot_seed$seed.log" | tail -1))"
}
export -f run_one
export bin objects trials out

for seed in $seeds; do
  "$bin/telegrasp-test-domains" bash -c "run_one $seed"
done

# Per object over every seed: held / trials, and the reasons of the misses.
python3 - "$target" "$out" $seeds <<'EOF'
import json, sys, collections
target, out, seeds = float(sys.argv[1]), sys.argv[2], sys.argv[3:]
held, n, why = collections.Counter(), collections.Counter(), collections.defaultdict(list)
for s in seeds:
    try:
        grasps = json.load(open(f"{out}/bot_seed{s}.json"))["grasps"]
    except (OSError, ValueError) as e:
        print(f"seed {s}: no records ({e})"); grasps = []
    for g in grasps:
        o = g["object"]; n[o] += 1; held[o] += bool(g["held_after_lift"])
        if not g["held_after_lift"]: why[o].append(f"seed {s}: {g.get('reason')}")
bad = 0
for o in sorted(n):
    ok = 100.0 * held[o] / n[o] >= target
    bad += not ok
    print(f"{o:28s} held {held[o]}/{n[o]}" + ("" if ok else "  BELOW TARGET") + "".join("\n    " + w for w in why[o]))
print(f"total held {sum(held.values())}/{sum(n.values())} on {len(n)} objects; {bad} below {target:g} %; records in {out}")
sys.exit(1 if bad or not n else 0)
EOF
