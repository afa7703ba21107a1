#!/usr/bin/env bash
# Checks the unit calstandd.service, as generated from daemon/calstandd.service.in for the
# install, with systemd-analyze: every key known, every section well formed, the ExecStart
# binary present (the one just built stands in for the installed one). Any complaint fails.
#   check_systemd_unit.sh UNIT INSTALLED_CALSTANDD CALSTANDD_BINARY
set -euo pipefail
unit="$1"
installed="$2"
binary="$3"
if ! command -v systemd-analyze >/dev/null; then
  echo "systemd-analyze is not installed (package systemd): cannot check $unit" >&2
  exit 1
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
grep -q "^ExecStart=$installed " "$unit" || { echo "$unit: no ExecStart of $installed" >&2; exit 1; }
grep -q "^Type=notify$" "$unit" || { echo "$unit: not Type=notify" >&2; exit 1; }
grep -q "^WatchdogSec=" "$unit" || { echo "$unit: no WatchdogSec" >&2; exit 1; }
sed "s|^ExecStart=$installed |ExecStart=$binary |" "$unit" > "$work/calstandd.service"
# --man=no: the man pages Documentation= names are installed with the package, not here
# (tests/packaging/check_cli_docs.sh checks them).
said="$(systemd-analyze verify --man=no "$work/calstandd.service" 2>&1 || true)"
if [ -n "$said" ]; then
  echo "systemd-analyze verify $unit:" >&2
  echo "$said" >&2
  exit 1
fi
echo "$unit: systemd-analyze verify found nothing to complain about"
