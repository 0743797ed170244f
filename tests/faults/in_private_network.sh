#!/bin/sh
# Runs a command in a network namespace of its own with only `lo`, up: nothing it sends leaves it.
# Exit 77 (ctest's skip) when that cannot be done (not root, no unshare or ip).
if ! unshare -n true 2>/dev/null || ! command -v ip >/dev/null; then
  echo "in_private_network: cannot make a network namespace (needs root, unshare and ip): skipped" >&2
  exit 77
fi
exec unshare -n sh -c 'ip link set lo up && exec "$@"' sh "$@"
