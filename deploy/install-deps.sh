#!/usr/bin/env bash
# Installs every Debian package telegrasp needs to build, test and run, then the npm packages of
# tests/js (the reference MCAP reader the tests check telegrasp's recordings with, the Foxglove
# client, playwright-core and the IWER headset emulator for telegrasp-view's tests) and of
# client_lib/tools/view/web (three.js, the generic hand glTF of @webxr-input-profiles/assets and
# @foxglove/schemas, which telegrasp-view's pages and schemas are built from). Idempotent and
# quiet when everything is present. Run as root (or with sudo available) on Debian 12.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

packages=(
  build-essential cmake pkg-config ccache
  libeigen3-dev libbullet-dev libbullet-extras-dev libassimp-dev libqhull-dev
  libprotobuf-dev protobuf-compiler nlohmann-json3-dev
  libfastrtps-dev libfastcdr-dev fastddsgen fastdds-tools
  libgtest-dev libgmock-dev libbenchmark-dev
  libzstd-dev openssl libssl-dev
  libboost-dev chromium
  iptables iproute2
)
# The sanitizer and fuzzer builds (deploy/run-sanitizers.sh, run-fuzz.sh) ask for clang.
[ "${TELEGRASP_DEPS_SANITIZERS:-0}" = 1 ] && packages+=(clang libclang-rt-14-dev llvm)
# Node.js runs tests/js; a machine with its own node on PATH keeps it.
command -v node >/dev/null || packages+=(nodejs npm)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "install-deps: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
    sudo="sudo"
  fi
  echo "install-deps: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# npm packages: exactly the versions in each package-lock.json, reinstalled when the lock is newer.
for dir in tests/js client_lib/tools/view/web; do
  js="$root/$dir"
  if [ ! -d "$js/node_modules" ] || [ "$js/node_modules" -ot "$js/package-lock.json" ]; then
    echo "install-deps: npm ci in $dir" >&2
    (cd "$js" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
  fi
done
