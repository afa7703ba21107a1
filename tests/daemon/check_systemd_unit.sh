#!/usr/bin/env bash
# Checks the example unit daemon/calstandd.service with systemd-analyze: every key known, every
# section well formed, the ExecStart binary present (the one just built stands in for
# /usr/local/bin/calstandd). Any complaint fails the test.
#   check_systemd_unit.sh UNIT CALSTANDD_BINARY
set -euo pipefail
unit="$1"
binary="$2"
if ! command -v systemd-analyze >/dev/null; then
  echo "systemd-analyze is not installed (package systemd): cannot check $unit" >&2
  exit 1
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
sed "s|/usr/local/bin/calstandd|$binary|" "$unit" > "$work/calstandd.service"
grep -q "$binary" "$work/calstandd.service" || { echo "$unit: no ExecStart of /usr/local/bin/calstandd" >&2; exit 1; }
said="$(systemd-analyze verify "$work/calstandd.service" 2>&1 || true)"
if [ -n "$said" ]; then
  echo "systemd-analyze verify $unit:" >&2
  echo "$said" >&2
  exit 1
fi
echo "$unit: systemd-analyze verify found nothing to complain about"
