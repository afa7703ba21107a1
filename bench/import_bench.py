#!/usr/bin/python3
"""Import speed and memory (issue 32): `calstand import` of an MCAP file with zstd chunks, and
of the same samples as a calstand-import/2 CSV folder, side by side with numpy.loadtxt reading
the CSV, in one run. Prints seconds, samples per second and peak resident memory of each.

    import_bench.py CALSTAND_BIN [--samples N] [--keep DIR] [--csv-only] [--compare OTHER_BIN]

--csv-only writes and imports only the CSV folder (numpy writes it, quickly); --compare also
imports the CSV folder with another calstand binary (e.g. one built before a change), side by
side. Each import's peak resident memory is checked against the issue's bar: 2 M samples under
300 MB, memory independent of the length.

The recording is written by tests/support/write_recordings.py's MCAP and CDR writers, chunk by
chunk (1 MiB of records per chunk, as ROS 2's recorder writes them), from the MCAP
specification. Needs Debian's python3-numpy and python3-zstandard.
"""

import os
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests",
                                "support"))
import write_recordings as w  # noqa: E402


def write_inputs(folder, n):
    import random
    import zstandard
    rnd = random.Random(3)
    comp = zstandard.ZstdCompressor()
    os.makedirs(os.path.join(folder, "csv"), exist_ok=True)
    with open(os.path.join(folder, "csv", "meta.json"), "w") as f:
        f.write('{"format": "calstand-import/2", "site": {"latitude_deg": 45.0, "height_m": 0.0, '
                '"gravity_mps2": 9.8062}, "sample_rate_hz": 400, '
                '"units": {"gyro": "rad/s", "accel": "m/s^2", "time": "s"}}\n')
    csv = open(os.path.join(folder, "csv", "samples.csv"), "w")
    csv.write("t,gx,gy,gz,ax,ay,az\n")
    mcap = open(os.path.join(folder, "imu.mcap"), "wb")
    mcap.write(w.MAGIC)
    mcap.write(w.rec(0x01, w.s32("ros2") + w.s32("calstand import bench")))
    defs = w.rec(0x03, struct.pack("<H", 1) + w.s32("sensor_msgs/msg/Imu") + w.s32("ros2msg") +
                 w.s32(w.IMU_MSG))
    defs += w.rec(0x04, struct.pack("<HH", 1, 1) + w.s32("/imu/data") + w.s32("cdr") +
                  struct.pack("<I", 0))
    records = bytearray(defs)
    t0 = 1700000000 * 10**9
    first = None
    lines = []
    for i in range(n):
        stamp = t0 + i * 2_500_000  # 400 Hz
        g = [rnd.gauss(0.0, 0.01) for _ in range(3)]
        a = [rnd.gauss(0.0, 0.02), rnd.gauss(0.0, 0.02), 9.80665 + rnd.gauss(0.0, 0.02)]
        if first is None:
            first = stamp
        records += w.rec(0x05, struct.pack("<HIQQ", 1, i, stamp, stamp) + w.cdr_imu(stamp, g, a))
        lines.append(",".join(repr(v) for v in [w.seconds(stamp)] + g + a))
        if len(records) >= 1 << 20 or i == n - 1:
            packed = comp.compress(bytes(records))
            mcap.write(w.rec(0x06, struct.pack("<QQQI", first, stamp, len(records),
                                               zlib.crc32(records)) + w.s32("zstd") +
                             struct.pack("<Q", len(packed)) + packed))
            records = bytearray()
            first = None
            csv.write("\n".join(lines) + "\n")
            lines = []
    mcap.write(w.rec(0x0F, struct.pack("<I", 0)))
    mcap.write(w.rec(0x02, struct.pack("<QQI", 0, 0, 0)))
    mcap.write(w.MAGIC)
    mcap.close()
    csv.close()


def write_csv_only(folder, n):
    import numpy as np
    rng = np.random.default_rng(3)
    os.makedirs(os.path.join(folder, "csv"), exist_ok=True)
    with open(os.path.join(folder, "csv", "meta.json"), "w") as f:
        f.write('{"format": "calstand-import/2", "site": {"latitude_deg": 45.0, "height_m": 0.0, '
                '"gravity_mps2": 9.8062}, "sample_rate_hz": 400, '
                '"units": {"gyro": "rad/s", "accel": "m/s^2", "time": "s"}}\n')
    with open(os.path.join(folder, "csv", "samples.csv"), "w") as f:
        f.write("t,gx,gy,gz,ax,ay,az\n")
        for i in range(0, n, 200_000):
            k = min(n, i + 200_000) - i
            t = 1700000000.0 + (i + np.arange(k)) * 0.0025
            g = rng.normal(0.0, 0.01, (k, 3))
            a = rng.normal(0.0, 0.02, (k, 3)) + [0.0, 0.0, 9.80665]
            np.savetxt(f, np.column_stack([t, g, a]), fmt="%.17g", delimiter=",")


BAR_MB = 300.0


def main():
    args = sys.argv[1:]
    calstand = args[0]
    n = int(args[args.index("--samples") + 1]) if "--samples" in args else 2_000_000
    keep = args[args.index("--keep") + 1] if "--keep" in args else None
    csv_only = "--csv-only" in args
    compare = args[args.index("--compare") + 1] if "--compare" in args else None
    folder = keep or tempfile.mkdtemp(prefix="calstand-import-bench-")
    if csv_only:
        if not os.path.exists(os.path.join(folder, "csv", "samples.csv")):
            print(f"writing {n} rows of CSV to {folder} ...", flush=True)
            write_csv_only(folder, n)
    elif not os.path.exists(os.path.join(folder, "imu.mcap")):
        print(f"writing {n} samples (MCAP zstd and CSV) to {folder} ...", flush=True)
        write_inputs(folder, n)
    csv_mb = os.path.getsize(os.path.join(folder, "csv", "samples.csv")) / 1e6
    if csv_only:
        print(f"{n} samples: samples.csv {csv_mb:.0f} MB")
    else:
        mcap_mb = os.path.getsize(os.path.join(folder, "imu.mcap")) / 1e6
        print(f"{n} samples: imu.mcap {mcap_mb:.0f} MB (zstd), samples.csv {csv_mb:.0f} MB")

    results = {}
    loadtxt = ("/usr/bin/python3", "-c",
               "import numpy, sys; numpy.loadtxt(sys.argv[1], delimiter=',', skiprows=1)",
               os.path.join(folder, "csv", "samples.csv"))
    # ru_maxrss of RUSAGE_CHILDREN is the maximum over all children so far, so each tool runs
    # under a fresh python wrapper that reports its own child's time and peak.
    tools = [("numpy.loadtxt (CSV)", list(loadtxt))]
    if not csv_only:
        tools.append(("calstand import (MCAP zstd)",
                      [calstand, "import", os.path.join(folder, "imu.mcap"), "--db",
                       os.path.join(folder, "mcap.db"), "--latitude", "45", "--height", "0"]))
    tools.append(("calstand import (CSV folder)",
                  [calstand, "import", os.path.join(folder, "csv"), "--db",
                   os.path.join(folder, "csv.db")]))
    if compare:
        tools.append(("compare: import (CSV folder)",
                      [compare, "import", os.path.join(folder, "csv"), "--db",
                       os.path.join(folder, "csv.db")]))
    for name, cmd in tools:
        for db in ("mcap.db", "csv.db"):
            for suffix in ("", "-wal", "-shm"):
                p = os.path.join(folder, db + suffix)
                if os.path.exists(p):
                    os.remove(p)
        wrapper = ("/usr/bin/python3", "-c",
                   "import resource, subprocess, sys, time; s = time.perf_counter(); "
                   "subprocess.run(sys.argv[1:], check=True, stdout=subprocess.DEVNULL); "
                   "e = time.perf_counter() - s; "
                   "print(e, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")
        out = subprocess.run(list(wrapper) + cmd, check=True, capture_output=True, text=True)
        seconds, rss_kb = out.stdout.split()
        results[name] = (float(seconds), float(rss_kb) / 1024.0)
        print(f"{name:32s} {float(seconds):7.2f} s  {n / float(seconds) / 1e6:6.2f} M samples/s  "
              f"peak {float(rss_kb) / 1024.0:7.1f} MB", flush=True)
    base = results["numpy.loadtxt (CSV)"][0]
    for name, (s, _) in results.items():
        print(f"{name:32s} {s / base:5.2f} x numpy.loadtxt")
    # The bar: 2 M samples under 300 MB resident (and memory flat in the length).
    for name, (_, rss) in results.items():
        if "import" in name:
            print(f"{name:32s} peak {rss:7.1f} MB: {'under' if rss < BAR_MB else 'OVER'} "
                  f"the issue's {BAR_MB:.0f} MB")
    if keep is None:
        shutil.rmtree(folder)


if __name__ == "__main__":
    main()
