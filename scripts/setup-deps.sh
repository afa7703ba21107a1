#!/usr/bin/env bash
# Installs every build and test dependency of calstand from Debian packages, then the web
# console's npm dependency (uPlot, console/package-lock.json), which CMake embeds in calstandd.
# Idempotent: when everything is already installed it only checks (no apt-get update, no npm).
# Works as root on a bare Debian machine; uses sudo when run as another user.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

packages=(
  build-essential cmake pkg-config ninja-build clang-format
  libeigen3-dev nlohmann-json3-dev libcli11-dev libspdlog-dev libfmt-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libsqlite3-dev libsqlitecpp-dev libssl-dev openssl sqlite3 libfast-float-dev
  liblz4-dev libzstd-dev libbz2-dev libisal-dev python3-rosbag python3-zstandard python3-lz4
  python3-numpy
  libpqxx-dev postgresql
  libmuparser-dev libfftw3-dev libboost-math-dev libceres-dev
  libmodbus-dev python3-pymodbus python3-serial python3-serial-asyncio libcpp-httplib-dev
  json-schema-test-suite
  gnuplot-nox chromium chromium-driver python3-selenium
  nodejs node-eventsource
  systemd
  python3 groff-base  # the man pages and completion are made at build time (python3); ctest renders them (groff)
)

missing=()
# Debian's nodejs needs its npm package; a node from elsewhere (NodeSource) brings its own npm.
if ! command -v npm >/dev/null 2>&1; then packages+=(npm); fi
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup-deps: all ${#packages[@]} packages present"
else
  sudo_cmd=()
  if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
  echo "setup-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The console's npm packages, exactly as locked, only when they are missing or the lock file
# changed since the last install (npm keeps its own copy of the lock in node_modules).
console="$root/console"
installed_lock="$console/node_modules/.package-lock.json"
if [ ! -f "$console/node_modules/uplot/dist/uPlot.iife.min.js" ] || [ ! -f "$installed_lock" ] ||
   [ "$console/package-lock.json" -nt "$installed_lock" ]; then
  echo "setup-deps: npm ci in console/"
  (cd "$console" && npm ci --no-audit --no-fund --loglevel=error)
fi
