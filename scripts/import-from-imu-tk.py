#!/usr/bin/env python3
"""Converts an imu_tk recording (two ASCII files, `t ax ay az` and `t gx gy gz`, one row per
sample, raw counts; e.g. imu_tk's bin/test_data/xsens_acc.mat and xsens_gyro.mat) into a
calstand-import/2 folder (meta.json, samples.csv) without table columns or steps: `calstand
import` then stores it as one recording, and `calstand fit` finds its static poses and
calibrates it by the gravity norm and by integration between the poses.

The nominal conversion is the datasheet's (a raw count is (counts - offset) / counts_per_unit);
every fitted parameter is relative to it. The defaults are the ones error-model.md's /2 example
gives for this Xsens MTi recording: offset 32768 counts, 83.78 counts per deg/s, 410 counts per
m/s^2. Site: Padova (imu_tk's own |g| = 9.81744 m/s^2).

Usage: scripts/import-from-imu-tk.py ACC_FILE GYRO_FILE OUT_DIR [--rate-hz 100] [...]
Standard library only."""
import argparse
import json
import os
import sys


def read_rows(path):
    rows = []
    with open(path) as f:
        for number, line in enumerate(f, 1):
            fields = line.split()
            if not fields:
                continue
            if len(fields) != 4:
                sys.exit(f"{path}:{number}: expected 4 columns (t x y z), got {len(fields)}")
            try:
                rows.append([float(v) for v in fields])
            except ValueError as e:
                sys.exit(f"{path}:{number}: {e}")
    if not rows:
        sys.exit(f"{path}: no samples")
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("acc")
    p.add_argument("gyro")
    p.add_argument("out")
    p.add_argument("--rate-hz", type=float, default=100.0)
    p.add_argument("--offset-counts", type=float, default=32768.0)
    p.add_argument("--gyro-counts-per-dps", type=float, default=83.78)
    p.add_argument("--accel-counts-per-mps2", type=float, default=410.0)
    p.add_argument("--latitude-deg", type=float, default=45.41)
    p.add_argument("--height-m", type=float, default=12.0)
    p.add_argument("--gravity-mps2", type=float, default=9.81744)
    a = p.parse_args()

    acc = read_rows(a.acc)
    gyro = read_rows(a.gyro)
    if len(acc) != len(gyro):
        sys.exit(f"{a.acc} has {len(acc)} rows and {a.gyro} {len(gyro)}: not one sample per row")
    for i, (ra, rg) in enumerate(zip(acc, gyro)):
        if abs(ra[0] - rg[0]) > 1e-9:
            sys.exit(f"row {i + 1}: the accelerometer's time {ra[0]} is not the gyro's {rg[0]}")

    os.makedirs(a.out, exist_ok=True)
    o = a.offset_counts
    meta = {
        "format": "calstand-import/2",
        "site": {"latitude_deg": a.latitude_deg, "height_m": a.height_m,
                 "gravity_mps2": a.gravity_mps2},
        "sample_rate_hz": a.rate_hz,
        "units": {"gyro": "counts", "accel": "counts", "time": "s"},
        "nominal": {
            "gyro": {"offset_counts": [o, o, o], "counts_per_dps": [a.gyro_counts_per_dps] * 3},
            "accel": {"offset_counts": [o, o, o],
                      "counts_per_mps2": [a.accel_counts_per_mps2] * 3},
        },
    }
    with open(os.path.join(a.out, "meta.json"), "w") as f:
        json.dump(meta, f, indent=2)
        f.write("\n")
    with open(os.path.join(a.out, "samples.csv"), "w") as f:
        f.write("t,gx,gy,gz,ax,ay,az\n")
        for ra, rg in zip(acc, gyro):
            f.write("%.6f,%g,%g,%g,%g,%g,%g\n" % (ra[0], rg[1], rg[2], rg[3], ra[1], ra[2], ra[3]))
    print(f"{a.out}: {len(acc)} samples, {acc[0][0]:.3f} to {acc[-1][0]:.3f} s")


if __name__ == "__main__":
    try:
        main()
    except OSError as e:  # an input that cannot be read, or an output that cannot be written
        sys.exit(f"{e.filename}: {e.strerror}")
