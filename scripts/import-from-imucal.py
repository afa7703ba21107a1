#!/usr/bin/env python3
"""Converts an imucal Ferraris session into a calstand-import/2 folder (meta.json with the
section labels, samples.csv with a `step` per section). Two forms, as imucal stores them:

  annotated: one CSV with a `part` column naming each sample's section (x_p, x_a, ..., x_rot,
             ...), a `samples` column (the sample index) and raw counts acc_x..z, gyr_x..z
             (imucal's example_data/annotated_session.csv, 204.8 Hz);
  session:   one CSV n_samples,gyr_x..z (deg/s),acc_x..z (m/s^2) and a JSON section list
             {"x_p": {"start": S, "end": E}, ...} whose sections are rows [S, E) (imucal's
             example_data/example_ferraris_session.csv with _list.json, 102.4 Hz).

Only the samples of the nine sections are written (the annotated form holds nothing else).
Sections: `<axis>_p` is a hold with that body axis up (the accelerometer reads +g on it),
`<axis>_a` with it down, `<axis>_rot` a turn of 360 deg about that axis, whose sign calstand
takes from the data (imucal's own default is -360, clockwise).

The nominal conversion of raw counts is the datasheet's: imucal's sensor fits a +-16 g,
+-2000 deg/s part (2048 counts per g, 16.384 counts per deg/s, offset 0); every fitted
parameter is relative to it. g is imucal's 9.81 m/s^2, at Erlangen.

Usage: scripts/import-from-imucal.py annotated FILE.csv OUT_DIR [--rate-hz 204.8]
       scripts/import-from-imucal.py session FILE.csv SECTIONS.json OUT_DIR [--rate-hz 102.4]
Standard library only."""
import argparse
import csv
import json
import os
import sys

SECTIONS = ["x_p", "x_a", "y_p", "y_a", "z_p", "z_a", "x_rot", "y_rot", "z_rot"]


def section_meta(label):
    axis = label[0]
    if label.endswith("_rot"):
        return {"label": label, "kind": "turn", "axis": "+" + axis, "angle_deg": 360}
    return {"label": label, "kind": "static", "up": ("+" if label.endswith("_p") else "-") + axis}


def write(out, rate_hz, units, nominal, rows, gravity, latitude):
    """rows: (t, step, gx, gy, gz, ax, ay, az)."""
    os.makedirs(out, exist_ok=True)
    meta = {
        "format": "calstand-import/2",
        "site": {"latitude_deg": latitude, "height_m": 280.0, "gravity_mps2": gravity},
        "sample_rate_hz": rate_hz,
        "units": units,
        "sections": {str(SECTIONS.index(l) + 1): section_meta(l) for l in SECTIONS},
    }
    if nominal:
        meta["nominal"] = nominal
    with open(os.path.join(out, "meta.json"), "w") as f:
        json.dump(meta, f, indent=2)
        f.write("\n")
    with open(os.path.join(out, "samples.csv"), "w") as f:
        f.write("t,step,gx,gy,gz,ax,ay,az\n")
        for r in rows:
            f.write("%.6f,%d,%r,%r,%r,%r,%r,%r\n" % r)
    print(f"{out}: {len(rows)} samples in {len({r[1] for r in rows})} sections")


def annotated(a):
    rows = []
    with open(a.csv) as f:
        for number, rec in enumerate(csv.DictReader(f), 2):
            part = rec["part"]
            if part not in SECTIONS:
                sys.exit(f"{a.csv}:{number}: part {part!r} is not one of {SECTIONS}")
            t = float(rec["samples"]) / a.rate_hz
            rows.append((t, SECTIONS.index(part) + 1,
                         float(rec["gyr_x"]), float(rec["gyr_y"]), float(rec["gyr_z"]),
                         float(rec["acc_x"]), float(rec["acc_y"]), float(rec["acc_z"])))
    rows.sort(key=lambda r: r[0])
    zero = [0.0, 0.0, 0.0]
    nominal = {"gyro": {"offset_counts": zero, "counts_per_dps": [16.384] * 3},
               "accel": {"offset_counts": zero, "counts_per_mps2": [2048 / 9.81] * 3}}
    write(a.out, a.rate_hz, {"gyro": "counts", "accel": "counts", "time": "s"}, nominal, rows,
          9.81, 49.60)


def session(a):
    with open(a.sections) as f:
        spans = json.load(f)
    missing = [l for l in SECTIONS if l not in spans]
    if missing:
        sys.exit(f"{a.sections}: sections {missing} are missing")
    step_of = {}
    for label in SECTIONS:
        for i in range(int(spans[label]["start"]), int(spans[label]["end"])):
            step_of[i] = SECTIONS.index(label) + 1
    rows = []
    with open(a.csv) as f:
        for rec in csv.DictReader(f):
            i = int(rec["n_samples"])
            if i in step_of:
                rows.append((i / a.rate_hz, step_of[i],
                             float(rec["gyr_x"]), float(rec["gyr_y"]), float(rec["gyr_z"]),
                             float(rec["acc_x"]), float(rec["acc_y"]), float(rec["acc_z"])))
    write(a.out, a.rate_hz, {"gyro": "deg/s", "accel": "m/s^2", "time": "s"}, None, rows,
          9.81, 49.60)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="form", required=True)
    an = sub.add_parser("annotated")
    an.add_argument("csv")
    an.add_argument("out")
    an.add_argument("--rate-hz", type=float, default=204.8)
    se = sub.add_parser("session")
    se.add_argument("csv")
    se.add_argument("sections")
    se.add_argument("out")
    se.add_argument("--rate-hz", type=float, default=102.4)
    a = p.parse_args()
    annotated(a) if a.form == "annotated" else session(a)


if __name__ == "__main__":
    try:
        main()
    except OSError as e:  # an input that cannot be read, or an output that cannot be written
        sys.exit(f"{e.filename}: {e.strerror}")
