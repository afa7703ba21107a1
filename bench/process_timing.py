"""One program's wall time, peak memory and CPU time, shared by the Python benches.

The program runs under a fresh Python child, so that RUSAGE_CHILDREN holds only its figures
(the bench's own numpy or awk work would otherwise count towards the peak).
"""

import subprocess

TIMED = ("import resource, subprocess, sys, time; s = time.perf_counter(); "
         "subprocess.run(sys.argv[1:], check=True, stdout=subprocess.DEVNULL); "
         "e = time.perf_counter() - s; "
         "r = resource.getrusage(resource.RUSAGE_CHILDREN); "
         "print(e, r.ru_maxrss, r.ru_utime + r.ru_stime)")


def timed(cmd):
    """(wall s, peak RSS MB, CPU s) of running `cmd` to its end; raises if it fails."""
    out = subprocess.run(["/usr/bin/python3", "-c", TIMED] + cmd, check=True,
                         capture_output=True, text=True)
    seconds, rss_kb, cpu = out.stdout.split()
    return float(seconds), float(rss_kb) / 1024.0, float(cpu)
