#!/usr/bin/env bash
# Builds the libFuzzer harnesses of tests/fuzz (clang, ASan+UBSan, in build-asan, the build
# deploy/run-sanitizers.sh tests in) and runs each for a bounded time, from a seed corpus made of
# the repository's own files (rigs, the example configuration and questionnaire) and the seeds
# telegrasp-fuzz-seeds generates (CDR samples and commands, a recording, small meshes).
#
# usage: deploy/run-fuzz.sh [--duration-s S] [--runs N] [--seed N] [--only NAME] [--jobs J] [--corpus DIR]
#   --duration-s S  seconds per harness (default 60; --seconds: the old spelling)
#   --seed N      libFuzzer's random seed (default: a new one each run); the test command uses 1,
#                 so CI mutates the same inputs as a run checked here (only how far it gets varies)
#   --runs N      stop a harness after N executions instead (whichever comes first)
#   --only NAME   run one harness (controller-state, scene-command, server-config, rig-text,
#                 mesh, recording, questionnaire)
#   --jobs J      harnesses run at once (default 1)
#   --corpus DIR  where the growing corpora and any crash inputs go (default build-asan/fuzz)
# Prints per harness: executions, executions/s, corpus size, crashes; exits non-zero on any
# crash, leak, timeout or out-of-memory (the input is kept in DIR/<harness>/artifacts/).
set -euo pipefail
cd "$(dirname "$0")/.."
TELEGRASP_DEPS_SANITIZERS=1 deploy/install-deps.sh
root="$PWD"
seconds=60 runs=-1 seed=0 only="" jobs=1 corpus=""
usage() { sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'; }
while [ $# -gt 0 ]; do
  case "$1" in
    --duration-s) seconds="${2:?--duration-s needs a value}"; shift 2 ;;
    --seconds)  # the old spelling, for one release
      echo "run-fuzz: deprecated: --seconds is now --duration-s (--seconds goes in the next release)" >&2
      seconds="${2:?--seconds needs a value}"; shift 2 ;;
    --runs) runs="${2:?--runs needs a value}"; shift 2 ;;
    --seed) seed="${2:?--seed needs a value}"; shift 2 ;;
    --only) only="${2:?--only needs a harness name}"; shift 2 ;;
    --jobs) jobs="${2:?--jobs needs a value}"; shift 2 ;;
    --corpus) corpus="${2:?--corpus needs a folder}"; shift 2 ;;
    -h | --help) usage; exit 0 ;;
    *) echo "run-fuzz: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[[ "$seconds" =~ ^[1-9][0-9]*$ ]] || { echo "run-fuzz: --duration-s '$seconds' is not a positive integer" >&2; exit 2; }
[[ "$jobs" =~ ^[1-9][0-9]*$ ]] || { echo "run-fuzz: --jobs '$jobs' is not a positive integer" >&2; exit 2; }
[[ "$runs" =~ ^(-1|[1-9][0-9]*)$ ]] || { echo "run-fuzz: --runs '$runs' is not a positive integer" >&2; exit 2; }
[[ "$seed" =~ ^[0-9]{1,9}$ ]] || { echo "run-fuzz: --seed '$seed' is not a whole number below 10^9" >&2; exit 2; }
harnesses=(controller-state scene-command server-config rig-text mesh recording questionnaire)
if [ -n "$only" ]; then
  [[ " ${harnesses[*]} " == *" $only "* ]] || { echo "run-fuzz: --only '$only' is none of: ${harnesses[*]}" >&2; exit 2; }
  harnesses=("$only")
fi
build=build-asan
corpus="${corpus:-$root/$build/fuzz}"

launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
echo "run-fuzz: configure and build the harnesses in $build" >&2
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DTELEGRASP_SANITIZE=address \
  -DTELEGRASP_FUZZ=ON -DTELEGRASP_BUILD_BENCHMARKS=OFF "${launcher[@]}" >/dev/null
targets=(telegrasp-fuzz-seeds)
for h in "${harnesses[@]}"; do targets+=("telegrasp-fuzz-$h"); done
mkdir -p "$corpus"
cmake --build "$build" -j"$(nproc)" --target "${targets[@]}" >"$corpus/build.log" 2>&1 ||
  { tail -40 "$corpus/build.log"; echo "run-fuzz: build failed (log: $corpus/build.log)" >&2; exit 1; }

# Seeds: generated ones, then the repository's files of each format.
seeds="$corpus/seeds"
rm -rf "$seeds"
"$build/bin/telegrasp-fuzz-seeds" "$seeds"
mkdir -p "$seeds/rig_text" "$seeds/server_config" "$seeds/questionnaire"
cp sim/rigs/*.textproto "$seeds/rig_text/"
cp deploy/server.example.textproto "$seeds/server_config/"
cp deploy/examples/questionnaire.example.csv "$seeds/questionnaire/"
cp -r tests/fuzz/corpus/. "$seeds/" 2>/dev/null || true  # committed seeds, if any

# libFuzzer: every sanitizer report fatal, leaks checked, 10 s per input at most (a hang), 2 GB
# of memory at most (the 2e9-vertex PLY asked for 9.45 GB).
export ASAN_OPTIONS="halt_on_error=1:abort_on_error=1:detect_leaks=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:${UBSAN_OPTIONS:-}"
export LSAN_OPTIONS="suppressions=$root/tests/sanitizers/lsan.supp:print_suppressions=0:${LSAN_OPTIONS:-}"

run_one() {
  local h="$1" dir="$corpus/$1"
  local seed_dir="$seeds/${h//-/_}"
  rm -rf "$dir/rc" "$dir/artifacts"  # each run reports only its own findings
  mkdir -p "$dir/corpus" "$dir/artifacts"
  [ -d "$seed_dir" ] || mkdir -p "$seed_dir"
  "$root/$build/bin/telegrasp-fuzz-$h" "$dir/corpus" "$seed_dir" -max_total_time="$seconds" -runs="$runs" -seed="$seed" \
    -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=2048 -max_len=65536 -print_final_stats=1 \
    -artifact_prefix="$dir/artifacts/" >"$dir/log" 2>&1 && echo 0 >"$dir/rc" || echo $? >"$dir/rc"
}

pids=() names=()
for h in "${harnesses[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do wait -n || true; done
  echo "run-fuzz: $h for ${seconds}s$([ "$runs" != -1 ] && echo " or $runs runs")" >&2
  run_one "$h" &
  pids+=($!) names+=("$h")
done
status=0
printf '%-18s %12s %10s %8s %8s  %s\n' harness executions exec/s corpus crashes result
for i in "${!pids[@]}"; do
  h="${names[$i]}"
  wait "${pids[$i]}" 2>/dev/null || true
  rc="$(cat "$corpus/$h/rc" 2>/dev/null || echo '?')"
  log="$corpus/$h/log"
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  speed=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  size=$(find "$corpus/$h/corpus" -type f | wc -l)
  crashes=$(find "$corpus/$h/artifacts" -type f | wc -l)
  result=ok
  if [ "$rc" != 0 ] || [ "$crashes" != 0 ]; then
    result="FAILED (exit $rc; log $log)"
    status=1
  fi
  printf '%-18s %12s %10s %8s %8s  %s\n' "$h" "${execs:-?}" "${speed:-?}" "$size" "$crashes" "$result"
done
if [ "$status" != 0 ]; then
  for h in "${names[@]}"; do
    if grep -qE "ERROR: (libFuzzer|AddressSanitizer|LeakSanitizer|UndefinedBehaviorSanitizer)|runtime error:|==ERROR" "$corpus/$h/log"; then
      echo "---- $h: $(grep -m1 -E 'ERROR|runtime error' "$corpus/$h/log")" >&2
      grep -m3 -E "Test unit written|artifact" "$corpus/$h/log" >&2 || true
    fi
  done
fi
exit "$status"
