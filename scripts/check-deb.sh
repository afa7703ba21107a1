#!/usr/bin/env bash
# Checks the Debian package built by scripts/package-deb.sh: its control fields (the runtime
# libraries' packages by name), its contents against the tree (every schema and procedure,
# the programs, the unit, the conffiles, man pages, completion, docs; nothing elsewhere), the
# unpacked programs run (--version, --help, the daemon serves and stops), and lintian (no
# error; installed by apt when missing). Any failure exits 1 with what is wrong.
#   bash scripts/check-deb.sh [PACKAGE.deb]     default: the newest dist/calstand_*.deb
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
deb="${1:-$(ls -t "$root"/dist/calstand_*.deb 2>/dev/null | head -1)}"
[ -n "$deb" ] && [ -f "$deb" ] || { echo "check-deb: no package (bash scripts/package-deb.sh)" >&2; exit 1; }
version="$(sed -n 's/^project(calstand VERSION \([0-9.]*\).*/\1/p' "$root/CMakeLists.txt")"
work="$(mktemp -d)"
daemon_pid=""
trap '[ -n "$daemon_pid" ] && kill "$daemon_pid" 2>/dev/null; rm -rf "$work"' EXIT
failures=0
fail() { echo "check-deb: FAIL: $*" >&2; failures=$((failures + 1)); }
pass() { echo "check-deb: ok: $*"; }

# --- control fields -------------------------------------------------------------------------
field() { dpkg-deb -f "$deb" "$1"; }
[ "$(field Package)" = calstand ] || fail "Package is '$(field Package)'"
[ "$(field Version)" = "$version" ] || fail "Version '$(field Version)' is not the project's $version"
[ "$(field Architecture)" = "$(dpkg --print-architecture)" ] || fail "Architecture '$(field Architecture)'"
[ "$(basename "$deb")" = "calstand_${version}_$(dpkg --print-architecture).deb" ] ||
  fail "file name $(basename "$deb") is not calstand_VERSION_ARCH.deb"
depends="$(field Depends)"
# The libraries the programs link, by their Debian package (dpkg-shlibdeps), and the tools
# of the maintainer scripts.
# (Ceres is linked statically by libceres-dev: its own libraries, cholmod and glog, show.)
for p in libc6 libstdc++6 libsqlite3-0 libssl3 libpqxx libpq5 libmodbus5 libfmt libspdlog \
         libcpp-httplib libfftw3-double3 libmuparser libcholmod3 libgoogle-glog adduser; do
  [[ "$depends" == *"$p"* ]] || fail "Depends lacks $p: $depends"
done
pass "control: $(field Package) $(field Version) $(field Architecture); Depends: $depends"

# --- maintainer scripts and conffiles --------------------------------------------------------
dpkg-deb -e "$deb" "$work/control"
for s in postinst prerm postrm; do
  [ -x "$work/control/$s" ] || fail "no executable $s"
  sh -n "$work/control/$s" || fail "$s: not valid sh"
done
grep -q 'adduser --system' "$work/control/postinst" || fail "postinst makes no system user"
grep -q '/var/lib/calstand' "$work/control/postinst" || fail "postinst makes no /var/lib/calstand"
grep -q 'deb-systemd-helper enable' "$work/control/postinst" &&
  ! grep -q 'was-enabled' "$work/control/postinst" && fail "postinst enables the unit unasked"
grep -q 'rmdir --ignore-fail-on-non-empty /var/lib/calstand' "$work/control/postrm" ||
  fail "postrm purge would not keep a database"
[ "$(sort "$work/control/conffiles")" = "$(printf '/etc/calstand/calstandd.conf\n/etc/calstand/station.json')" ] ||
  fail "conffiles: $(tr '\n' ' ' < "$work/control/conffiles")"
pass "maintainer scripts and conffiles"

# --- contents ---------------------------------------------------------------------------------
dpkg-deb -c "$deb" | awk '{print $6}' | sed 's|^\./|/|; s|/$||' | sort > "$work/contents"
expected=(/usr/bin/calstand /usr/sbin/calstandd /lib/systemd/system/calstandd.service
          /etc/calstand/calstandd.conf /etc/calstand/station.json
          /usr/share/man/man1/calstand.1.gz /usr/share/man/man8/calstandd.8.gz
          /usr/share/bash-completion/completions/calstand
          /usr/share/bash-completion/completions/calstandd
          /usr/share/doc/calstand/copyright /usr/share/doc/calstand/changelog.gz
          /usr/share/doc/calstand/README.md /usr/share/calstand/schemas/api.md)
for f in "$root"/schemas/*.json; do expected+=("/usr/share/calstand/schemas/$(basename "$f")"); done
for f in "$root"/procedures/library/*.json; do expected+=("/usr/share/calstand/procedures/$(basename "$f")"); done
for f in "$root"/docs/*.md; do expected+=("/usr/share/doc/calstand/$(basename "$f")"); done
for f in "${expected[@]}"; do grep -qx "$f" "$work/contents" || fail "the package lacks $f"; done
# Nothing outside the places a Debian package may use, and no build leftovers.
if grep -vE '^/(usr/(bin|sbin|share)|lib/systemd/system|etc/calstand)(/|$)|^/(usr|lib|etc|lib/systemd|usr/lib)?$' "$work/contents" | grep -v '^$' > "$work/stray"; then
  fail "files outside the expected places: $(tr '\n' ' ' < "$work/stray")"
fi
grep -E '\.(a|h|hpp|o)$|/include/' "$work/contents" && fail "build leftovers in the package"
pass "contents: ${#expected[@]} expected paths present, $(wc -l < "$work/contents") entries in all"

# --- the unpacked programs run ----------------------------------------------------------------
dpkg-deb -x "$deb" "$work/root"
bin="$work/root/usr/bin/calstand"
sbin="$work/root/usr/sbin/calstandd"
[ "$("$bin" --version)" = "calstand $version" ] || fail "calstand --version: $("$bin" --version)"
[ "$("$sbin" --version)" = "calstandd $version" ] || fail "calstandd --version: $("$sbin" --version)"
help="$("$bin" --help)"  # (not piped into grep -q: its early exit would fail the pipe)
grep -q '^Subcommands:' <<< "$help" || fail "calstand --help lists no subcommands"
help="$("$sbin" --help)"
grep -q -- '--db' <<< "$help" || fail "calstandd --help lists no --db"
file "$bin" "$sbin" | grep -q 'not stripped' && fail "the programs are not stripped"
grep -q '= 1 deg/s$' <<< "$("$bin" units "3600 deg/h" --to "deg/s")" ||
  fail "calstand units 3600 deg/h --to deg/s: $("$bin" units "3600 deg/h" --to "deg/s")"
# The daemon serves on the packaged station file (the simulator) and stops cleanly.
"$sbin" --db "$work/station.db" --station "$work/root/etc/calstand/station.json" \
  --listen 127.0.0.1:0 > "$work/daemon.out" 2> "$work/daemon.err" &
daemon_pid=$!
for _ in $(seq 100); do grep -q 'listening on' "$work/daemon.out" && break; sleep 0.1; done
url="$(sed -n 's/^calstandd: listening on \(http[^ ]*\)$/\1/p' "$work/daemon.out")"
if [ -z "$url" ]; then
  fail "calstandd did not serve: $(cat "$work/daemon.err")"
else
  python3 - "$url/station" <<'EOF' || fail "GET /station of the unpacked calstandd"
import json, sys, urllib.request
with urllib.request.urlopen(sys.argv[1], timeout=10) as r:
    station = json.load(r)
assert station, "empty /station"
EOF
  kill -TERM "$daemon_pid"
  wait "$daemon_pid" || fail "calstandd exit $? on SIGTERM: $(cat "$work/daemon.err")"
fi
daemon_pid=""
pass "unpacked programs: --version, --help, units, calstandd served $url and stopped"

# --- lintian ----------------------------------------------------------------------------------
if ! command -v lintian >/dev/null; then
  sudo_cmd=()
  [ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
  echo "check-deb: installing lintian"
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends lintian >/dev/null
fi
if lintian --fail-on error --display-info "$deb" > "$work/lintian" 2>&1; then
  pass "lintian: no error ($(grep -c '^W:' "$work/lintian" || true) warnings, $(grep -c '^I:' "$work/lintian" || true) notes)"
else
  fail "lintian found errors"
fi
cat "$work/lintian"

if [ "$failures" -ne 0 ]; then
  echo "check-deb: $failures check(s) failed on $deb" >&2
  exit 1
fi
echo "check-deb: $deb passes"
