#!/usr/bin/python3
"""A day at 1 kHz (86.4 M samples) through `calstand allan --csv` and `calstand noise-id --csv`
(issue 33, long records): seconds, samples per second and peak resident memory of the streamed
path (solver::DeviationStream) on the day, and of the streamed and the in-memory (today's, a
baseline build) paths on a tenth of it (8.64 M samples), so that the per-sample speed is
compared like for like where the in-memory path still fits.

    stream_day_bench.py CALSTAND_BIN --baseline BIN [--samples N] [--small N] [--keep DIR]
                        [--repeat R] [--stored N]

The record: one column `gx` [deg/s] at 1 kHz, a tactical gyro's white noise (0.005
deg/s/sqrt(Hz)), rate random walk (5e-4 deg/s/sqrt(s)) and a 0.3 deg/s bias, written with 9
significant digits (about 16 bytes a row: 1.4 GB for the day). The free space of the folder is
checked first; the files are deleted afterwards unless --keep. Each command is timed as a child
process (wall time, ru_maxrss, CPU time); the best of --repeat (default 1) is kept, the machine
being shared. --stored N also times `allan --db` and `noise-id --db` on a stored run of one
static step of N samples at 1 kHz (`calstand sim-session --kind static`, imported), both builds,
and `noise --db` on it (six channels' curves, terms and identified models; its default dense
taus read the step into memory, `--taus octave` streams it).
"""

import os
import shutil
import subprocess
import sys
import tempfile

from process_timing import timed

RATE_HZ = 1000.0


# awk (Box-Muller on its rand()): a hundred million rows in about a minute without numpy.
AWK_RECORD = r"""
BEGIN {
  srand(86400); pi = 3.141592653589793; walk = 0.0; print "gx"
  white = 0.005 * sqrt(rate); rrw = 5e-4 / sqrt(rate)
  for (i = 0; i < n; ++i) {
    u = rand(); if (u < 1e-300) u = 1e-300
    r = sqrt(-2.0 * log(u)); a = 2.0 * pi * rand()
    walk += rrw * r * sin(a)
    printf "%.9g\n", 0.3 + walk + white * r * cos(a)
  }
}
"""


def write_csv(day, n, part, small):
    """The day's record to `day`, its first `small` rows to `part`."""
    with open(day, "w") as f:
        subprocess.run(["awk", "-v", f"n={n}", "-v", f"rate={RATE_HZ}", AWK_RECORD], stdout=f,
                       check=True)
    with open(part, "w") as f:
        subprocess.run(["head", "-n", str(small + 1), day], stdout=f, check=True)


def main():
    args = sys.argv[1:]
    calstand = args[0]
    n = int(args[args.index("--samples") + 1]) if "--samples" in args else 86_400_000
    small = int(args[args.index("--small") + 1]) if "--small" in args else n // 10
    repeat = int(args[args.index("--repeat") + 1]) if "--repeat" in args else 1
    keep = args[args.index("--keep") + 1] if "--keep" in args else None
    baseline = args[args.index("--baseline") + 1] if "--baseline" in args else None
    folder = keep or tempfile.mkdtemp(prefix="calstand-stream-bench-", dir="/tmp")
    os.makedirs(folder, exist_ok=True)
    need = 17 * (n + small) * 1.2
    free = shutil.disk_usage(folder).free
    if free < need:
        sys.exit(f"{folder}: {free / 1e9:.1f} GB free, the CSV files need {need / 1e9:.1f} GB")
    day = os.path.join(folder, f"day-{n}.csv")
    part = os.path.join(folder, f"part-{small}.csv")
    try:
        if not (os.path.exists(day) and os.path.exists(part)):
            print(f"writing {n} and {small} rows to {folder} ...", flush=True)
            write_csv(day, n, part, small)
        print(f"{n} samples: {os.path.getsize(day) / 1e9:.2f} GB of CSV; "
              f"{small}: {os.path.getsize(part) / 1e9:.2f} GB")
        common = ["--column", "gx", "--rate", str(RATE_HZ), "--units", "deg/s", "--json"]
        runs = [
            ("allan, streamed", n, [calstand, "allan", "--csv", day] + common),
            ("noise-id, streamed", n, [calstand, "noise-id", "--csv", day] + common),
            ("allan, streamed", small, [calstand, "allan", "--csv", part] + common),
            ("noise-id, streamed", small, [calstand, "noise-id", "--csv", part] + common),
        ]
        stored = int(args[args.index("--stored") + 1]) if "--stored" in args else 0
        if stored:
            session, db = os.path.join(folder, "session"), os.path.join(folder, "stored.db")
            subprocess.run([calstand, "sim-session", "--kind", "static", "--rest",
                            str(stored / RATE_HZ), "--rate", str(RATE_HZ), "--out", session],
                           check=True, stdout=subprocess.DEVNULL)
            subprocess.run([calstand, "import", session, "--db", db], check=True,
                           stdout=subprocess.DEVNULL)
            shutil.rmtree(session)
            on_db = ["--db", db, "--run", "1", "--channel", "gx", "--json"]
            for name, binary in [("streamed", calstand), ("in memory (baseline)", baseline)]:
                if binary:
                    runs += [(f"allan --db, {name}", stored, [binary, "allan"] + on_db),
                             (f"noise-id --db, {name}", stored, [binary, "noise-id"] + on_db),
                             (f"noise --db, {name}", stored,
                              [binary, "noise", "--db", db, "--run", "1", "--json"]),
                             (f"noise --db --taus octave, {name}", stored,
                              [binary, "noise", "--db", db, "--run", "1", "--taus", "octave",
                               "--json"])]
        if baseline:
            runs += [
                ("allan, in memory (baseline)", small,
                 [baseline, "allan", "--csv", part] + common),
                ("noise-id, in memory (baseline)", small,
                 [baseline, "noise-id", "--csv", part] + common),
            ]
        best = {}
        for _ in range(repeat):
            for name, rows, cmd in runs:
                s, rss, cpu = timed(cmd)
                key = (name, rows)
                if key not in best or s < best[key][0]:
                    best[key] = (s, rss, cpu)
        for (name, rows), (s, rss, cpu) in best.items():
            print(f"{name:40s} {rows:>11,d} samples {s:8.2f} s  {rows / s / 1e6:6.2f} M samples/s"
                  f"  peak {rss:8.1f} MB  CPU {cpu:7.2f} s")
    finally:
        if keep is None:
            shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
