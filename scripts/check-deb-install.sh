#!/usr/bin/env bash
# The package's life on a machine: install, the daemon run as its user, remove, purge, with
# what each step must leave behind (docs/packaging.md, "Maintainer scripts"). It installs and
# purges calstand for real: run it as root on a machine or container meant for it (CI, a
# throw-away VM), where calstand is not installed and there is no user calstand. At the end
# the machine is as before (the user the test made is deleted too).
#   bash scripts/check-deb-install.sh [PACKAGE.deb]     default: the newest dist/calstand_*.deb
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
deb="${1:-$(ls -t "$root"/dist/calstand_*.deb 2>/dev/null | head -1)}"
[ -n "$deb" ] && [ -f "$deb" ] || { echo "check-deb-install: no package" >&2; exit 1; }
[ "$(id -u)" -eq 0 ] || { echo "check-deb-install: needs root (it installs the package)" >&2; exit 1; }
if dpkg-query -W calstand >/dev/null 2>&1 || getent passwd calstand >/dev/null || [ -e /var/lib/calstand ]; then
  echo "check-deb-install: calstand, its user or /var/lib/calstand is already here: not on this machine" >&2
  exit 1
fi
failures=0
fail() { echo "check-deb-install: FAIL: $*" >&2; failures=$((failures + 1)); }
pass() { echo "check-deb-install: ok: $*"; }
cleanup() {
  dpkg -P calstand >/dev/null 2>&1 || true
  rm -rf /var/lib/calstand
  if getent passwd calstand >/dev/null; then deluser --system calstand >/dev/null 2>&1 || true; fi
  if getent group calstand >/dev/null; then delgroup --system calstand >/dev/null 2>&1 || true; fi
}
trap cleanup EXIT

dpkg -i "$deb" >/dev/null
uid="$(getent passwd calstand | cut -d: -f3)"
[ -n "$uid" ] && [ "$uid" -lt 1000 ] || fail "no system user calstand (uid '$uid')"
[ "$(getent passwd calstand | cut -d: -f6)" = /var/lib/calstand ] || fail "calstand's home is not /var/lib/calstand"
[ "$(stat -c '%U:%G %a' /var/lib/calstand)" = "calstand:calstand 750" ] ||
  fail "/var/lib/calstand is $(stat -c '%U:%G %a' /var/lib/calstand)"
[ -f /lib/systemd/system/calstandd.service ] || fail "no unit installed"
ls /etc/systemd/system/*.wants/calstandd.service >/dev/null 2>&1 && fail "the unit was enabled on install"
for f in /etc/calstand/calstandd.conf /etc/calstand/station.json; do [ -f "$f" ] || fail "no $f"; done
pass "installed: user calstand (uid $uid), /var/lib/calstand 0750, the unit not enabled, conffiles"

# The daemon, as the unit runs it: its user, its database, the packaged options (setpriv
# execs it: the SIGTERM below reaches calstandd itself).
# shellcheck disable=SC1091
. /etc/calstand/calstandd.conf
# shellcheck disable=SC2086
setpriv --reuid=calstand --regid=calstand --init-groups /usr/sbin/calstandd --db /var/lib/calstand/station.db \
  ${CALSTANDD_OPTIONS/127.0.0.1:8765/127.0.0.1:0} > /tmp/check-deb-install.out 2>&1 &
pid=$!
for _ in $(seq 100); do grep -q 'listening on' /tmp/check-deb-install.out && break; sleep 0.1; done
kill -TERM "$pid"; wait "$pid" || fail "calstandd as calstand: exit $?: $(cat /tmp/check-deb-install.out)"
[ "$(stat -c %U /var/lib/calstand/station.db 2>/dev/null)" = calstand ] ||
  fail "calstandd as calstand made no database: $(cat /tmp/check-deb-install.out)"
rm -f /tmp/check-deb-install.out
pass "calstandd ran as calstand on /var/lib/calstand/station.db"

dpkg -r calstand >/dev/null
[ -f /var/lib/calstand/station.db ] || fail "remove deleted the database"
getent passwd calstand >/dev/null || fail "remove deleted the user"
[ -f /etc/calstand/calstandd.conf ] || fail "remove deleted the conffiles (purge does that)"
[ -e /usr/sbin/calstandd ] && fail "remove left the program"
pass "removed: database, user and conffiles kept"

dpkg -P calstand 2> /tmp/check-deb-install.err >/dev/null
[ -e /etc/calstand ] && fail "purge left /etc/calstand"
[ -f /var/lib/calstand/station.db ] || fail "purge deleted the station's database"
grep -q '/var/lib/calstand kept' /tmp/check-deb-install.err || fail "purge did not say it kept the database"
rm -f /tmp/check-deb-install.err
pass "purged: conffiles gone, the database kept with a note"

# With nothing of the station's in it, purge removes the directory the package made.
rm -f /var/lib/calstand/*
dpkg -i "$deb" >/dev/null
dpkg -P calstand >/dev/null 2>&1
[ -e /var/lib/calstand ] && fail "purge left an empty /var/lib/calstand"
pass "purged with no database: /var/lib/calstand gone"

if [ "$failures" -ne 0 ]; then echo "check-deb-install: $failures failure(s)" >&2; exit 1; fi
echo "check-deb-install: $deb installs, runs, removes and purges as it should"
