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
# ccache (a Debian package) lets every later build of the same sources reuse these objects: the
# sanitizer and fuzz builds on a warm cache, and CI's build without tools (.ci/run) at once. The
# cache keys on paths relative to the repository, so builds in other folders of it share it.
export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=true
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo "${launcher[@]}" >/dev/null
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure -j"$(nproc)"
[ "${TELEGRASP_TESTS_QUICK:-0}" = 1 ] && { echo "run-tests: TELEGRASP_TESTS_QUICK=1: sanitizers and fuzzing not run" >&2; exit 0; }
deploy/run-sanitizers.sh
deploy/run-fuzz.sh --duration-s 60 --seed 1 --jobs "$(nproc)"
