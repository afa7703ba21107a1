#!/usr/bin/env bash
# The demo campaign on the embedded simulator: a shortened thermal calibration (three plateaus,
# static positions and a rate ladder at each) of the demo station's IMU, then the loop of
# fit -> diagnose -> add the missing effect until the model fits to the noise floor, a
# calibration record, and the HTML report. Everything lands in $CALSTAND_DEMO_DIR (default
# ./demo-out). Expects a built calstand (scripts/run-demo.sh builds it first).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
calstand="${CALSTAND_BUILD_DIR:-$root/build}/cli/calstand"
out="${CALSTAND_DEMO_DIR:-$PWD/demo-out}"
mkdir -p "$out"
db="$out/demo.db"
rm -f "$db" "$db-wal" "$db-shm"

echo "== Campaign: thermal calibration of the demo station's IMU (3 plateaus) =="
"$calstand" run thermal-calibration --station "$root/sim/stations/demo.json" --db "$db" --quiet \
  --set 'temperatures=[-10,25,60]' --set soak_s=600 --set capture_s=20 \
  --set 'outer_angles=[0,90,180,270]' --set 'inner_angles=[0,90]' --set 'rates=[30,100,300]'
run=1

model="gyro_bias,gyro_scale,gyro_misalignment,earth_rate,accel_bias,accel_scale,accel_misalignment"
echo
echo "== Fit of the classical model =="
"$calstand" fit --db "$db" --run "$run" --model "$model"

# Diagnose, add the best candidate, again: until the diagnosis finds nothing missing.
for round in 1 2 3 4 5; do
  echo
  echo "== Diagnosis, round $round =="
  "$calstand" diagnose --db "$db" --run "$run" --model "$model"
  next="$("$calstand" diagnose --db "$db" --run "$run" --model "$model" --suggest)"
  [ -z "$next" ] && break
  echo "-> adding $next"
  model="$model,$next"
done

echo
echo "== Calibration record =="
"$calstand" calibrate --db "$db" --run "$run" --model "$model" --out "$out/calibration.json"
echo
echo "== How the error fell =="
"$calstand" history --db "$db" --run "$run"
echo
"$calstand" report --db "$db" --run "$run" --model "$model" --out "$out/report.html"
echo "report: $out/report.html   database: $db   record: $out/calibration.json"
