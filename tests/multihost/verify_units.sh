#!/usr/bin/env bash
# Checks the systemd template units of deploy/systemd with `systemd-analyze verify`, as instances
# (telegrasp-server@room-a, telegrasp-discovery@0), their /usr/local/bin programs replaced by those
# of a build. Any warning (an unknown key, a bad value) fails.
#
#   tests/multihost/verify_units.sh UNIT_DIR BIN_DIR
#
# Exit status: 0 they parse cleanly, 1 they do not, 2 a usage error, 77 no systemd-analyze (skipped).
set -euo pipefail

if [ "${1:-}" = -h ] || [ "${1:-}" = --help ]; then sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0; fi
[ $# = 2 ] || { echo "verify_units: expected UNIT_DIR BIN_DIR, got $# argument(s)" >&2; exit 2; }
units="$1"
bin="$2"
for f in "$units/telegrasp-server@.service" "$units/telegrasp-discovery@.service"; do
  [ -f "$f" ] || { echo "verify_units: UNIT_DIR '$units' has no $(basename "$f")" >&2; exit 2; }
done
[ -x "$bin/telegrasp-server" ] || { echo "verify_units: BIN_DIR '$bin' has no telegrasp-server" >&2; exit 2; }
bin="$(cd "$bin" && pwd)"  # ExecStart= needs an absolute path
command -v systemd-analyze >/dev/null || { echo "verify_units: no systemd-analyze: skipped" >&2; exit 77; }

work="$(mktemp -d -t telegrasp-units.XXXXXX)"
trap 'rm -rf "$work"' EXIT
for u in telegrasp-server@.service telegrasp-discovery@.service; do
  sed "s|/usr/local/bin/|$bin/|" "$units/$u" >"$work/$u"
done
ln -s telegrasp-server@.service "$work/telegrasp-server@room-a.service"
ln -s telegrasp-discovery@.service "$work/telegrasp-discovery@0.service"
status=0
(cd "$work" && systemd-analyze verify telegrasp-server@room-a.service telegrasp-discovery@0.service) \
  >"$work/out" 2>&1 || status=$?
if [ "$status" != 0 ] || grep -v '^$' "$work/out" | grep -q .; then
  echo "verify_units: systemd-analyze verify (exit $status) says:" >&2
  cat "$work/out" >&2
  exit 1
fi
echo "verify_units: telegrasp-server@.service and telegrasp-discovery@.service parse cleanly"
