#!/usr/bin/env bash
# The test command: installs dependencies, configures, builds and runs every test with ctest, then
# the sanitizer runs (deploy/run-sanitizers.sh: the unit and integration tests under
# AddressSanitizer + UndefinedBehaviorSanitizer, the server and client library tests under
# ThreadSanitizer) and every libFuzzer harness for 60 s (deploy/run-fuzz.sh). Exits non-zero if
# any of them fails. TELEGRASP_TESTS_QUICK=1 stops after ctest (a developer's quick run; CI runs
# everything).
set -euo pipefail
cd "$(dirname "$0")/.."
deploy/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure -j"$(nproc)"
[ "${TELEGRASP_TESTS_QUICK:-0}" = 1 ] && { echo "run-tests: TELEGRASP_TESTS_QUICK=1: sanitizers and fuzzing not run" >&2; exit 0; }
deploy/run-sanitizers.sh
deploy/run-fuzz.sh --duration-s 60 --seed 1 --jobs "$(nproc)"
