#!/usr/bin/env bash
# The main job on the embedded simulator, from a bare machine: installs the dependencies,
# builds, runs `calstand demo` (what the simulated IMU measures; extra arguments go to it, e.g.
# --seed 7), then the demo campaign (scripts/demo-campaign.sh): a thermal calibration ending in
# a fit, a diagnosis loop, a calibration record and an HTML report in ./demo-out.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/build.sh"
"${CALSTAND_BUILD_DIR:-$root/build}/cli/calstand" demo "$@"
echo
exec bash "$root/scripts/demo-campaign.sh"
