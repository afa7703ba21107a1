#!/usr/bin/python3
"""`calstand allan --csv` against numpy (issue 32): one column of a CSV of IMU rows
(t,gx,gy,gz,ax,ay,az at 400 Hz), read and turned into an overlapping Allan deviation at octave
averaging times, side by side in one run. Prints seconds, samples per second and peak resident
memory of each, and calstand's time as a multiple of numpy's.

    allan_csv_bench.py CALSTAND_BIN [--samples N] [--keep DIR] [--repeat R] [--baseline BIN]

numpy: `numpy.loadtxt(usecols=column)`, the mean removed, the phase as the cumulative sum, and
the overlapping Allan variance at m = 1, 2, 4, ... N/2 (NIST SP 1065 eq. 14) with vectorised
second differences: the fastest plain numpy way. calstand: `calstand allan --csv FILE --column gx
--rate 400 --json`, which also computes the degrees of freedom, the intervals and the noise fit.
Each run is timed as a child process (its wall time, ru_maxrss and CPU time); the best of --repeat runs
(default 3) is kept, since the machine is shared. `--baseline BIN` times another calstand build
(e.g. one from before a change) in the same rounds: before and after side by side in one run.
Needs Debian's python3-numpy.
"""

import os
import shutil
import sys
import tempfile

from process_timing import timed

NUMPY_ALLAN = r"""
import sys, numpy as np
y = np.loadtxt(sys.argv[1], delimiter=',', skiprows=1, usecols=(1,))
rate = float(sys.argv[2])
y = y - y.mean()
x = np.empty(y.size + 1); x[0] = 0.0; np.cumsum(y, out=x[1:]); x /= rate
n = y.size; tau0 = 1.0 / rate; m = 1; out = []
while 2 * m <= n:
    d = x[2 * m:] - 2.0 * x[m:-m] + x[:-2 * m]
    out.append((m * tau0, np.sqrt(np.dot(d, d) / (2.0 * (m * tau0) ** 2 * d.size))))
    m *= 2
print(len(out), out[0][1], file=sys.stderr)
"""


def write_csv(path, n):
    import numpy as np
    rng = np.random.default_rng(7)
    t = np.arange(n) / 400.0
    cols = [t] + [rng.normal(0.0, 1e-3, n) for _ in range(3)] + \
        [rng.normal(0.0, 1e-2, n), rng.normal(0.0, 1e-2, n), 9.80665 + rng.normal(0.0, 1e-2, n)]
    data = np.column_stack(cols)
    with open(path, "w") as f:
        f.write("t,gx,gy,gz,ax,ay,az\n")
        step = 200_000
        for i in range(0, n, step):
            np.savetxt(f, data[i:i + step], fmt="%.9g", delimiter=",")


def main():
    args = sys.argv[1:]
    calstand = args[0]
    n = int(args[args.index("--samples") + 1]) if "--samples" in args else 5_400_000
    repeat = int(args[args.index("--repeat") + 1]) if "--repeat" in args else 3
    keep = args[args.index("--keep") + 1] if "--keep" in args else None
    baseline = args[args.index("--baseline") + 1] if "--baseline" in args else None
    folder = keep or tempfile.mkdtemp(prefix="calstand-allan-bench-")
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, f"imu-{n}.csv")
    if not os.path.exists(path):
        print(f"writing {n} rows to {path} ...", flush=True)
        write_csv(path, n)
    print(f"{n} samples: {os.path.getsize(path) / 1e6:.0f} MB of CSV")
    tools = [("numpy loadtxt + cumsum ADEV", ["/usr/bin/python3", "-c", NUMPY_ALLAN, path, "400"]),
             ("calstand allan --csv", [calstand, "allan", "--csv", path, "--column", "gx",
                                       "--rate", "400", "--json"])]
    if baseline:
        tools.append(("calstand allan --csv (baseline)",
                      [baseline, "allan", "--csv", path, "--column", "gx", "--rate", "400",
                       "--json"]))
    best = {}
    for _ in range(repeat):
        for name, cmd in tools:  # interleaved, so that both see the same load
            s, rss, cpu = timed(cmd)
            if name not in best or s < best[name][0]:
                best[name] = (s, rss, cpu)
    for name, (s, rss, cpu) in best.items():
        print(f"{name:30s} {s:7.2f} s  {n / s / 1e6:6.2f} M samples/s  peak {rss:7.1f} MB  "
              f"CPU {cpu:6.2f} s")
    numpy, ours = best["numpy loadtxt + cumsum ADEV"], best["calstand allan --csv"]
    print(f"calstand allan --csv: {ours[0] / numpy[0]:.3f} x numpy's time "
          f"({ours[2] / numpy[2]:.3f} x its CPU time)")
    if baseline:
        base = best["calstand allan --csv (baseline)"]
        print(f"baseline:             {base[0] / numpy[0]:.3f} x numpy's time "
              f"({base[2] / numpy[2]:.3f} x its CPU time)")
    if keep is None:
        shutil.rmtree(folder)


if __name__ == "__main__":
    main()
