#!/usr/bin/env bash
# The main job on the embedded simulator, from a bare machine: installs the dependencies,
# builds, and runs `calstand demo` (extra arguments go to the demo, e.g. --json, --seed 7).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/build.sh"
exec "${CALSTAND_BUILD_DIR:-$root/build}/cli/calstand" demo "$@"
