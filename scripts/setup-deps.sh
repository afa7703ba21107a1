#!/usr/bin/env bash
# Installs every build and test dependency of calstand from Debian packages.
# Idempotent: when everything is already installed it only checks (no apt-get update).
# Works as root on a bare Debian machine; uses sudo when run as another user.
set -euo pipefail

packages=(
  build-essential cmake pkg-config ninja-build
  libeigen3-dev nlohmann-json3-dev libcli11-dev libspdlog-dev libfmt-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libsqlite3-dev libsqlitecpp-dev libssl-dev sqlite3
  libmuparser-dev libfftw3-dev libboost-math-dev
  libmodbus-dev python3-pymodbus python3-serial python3-serial-asyncio libcpp-httplib-dev
  json-schema-test-suite
  gnuplot-nox chromium
  nodejs node-eventsource
  systemd
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup-deps: all ${#packages[@]} packages present"
  exit 0
fi

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
echo "setup-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
