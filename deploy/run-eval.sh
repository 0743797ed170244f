#!/usr/bin/env bash
# The in-process evaluation (no network): installs dependencies, builds, and runs telegrasp-eval
# on the built-in objects (extra arguments go to telegrasp-eval, e.g. --objects ../shared/data/ycb).
set -euo pipefail
cd "$(dirname "$0")/.."
deploy/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j"$(nproc)" --target telegrasp-eval
exec build/bin/telegrasp-eval run "$@"
