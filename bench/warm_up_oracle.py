#!/usr/bin/python3
"""What the best possible test could find of issue 28's gyro warm-up on a MEMS- or an
ADIS16488-class unit: the oracle that knows the noise (white and wander, their true parameters)
and the warm-up's time constant. For each cell of calstand_warm_up_detection_bench (static
capture 0 or 1800 s, tau 300, 900, 1800 s, amplitude 5, 10, 20 times a 60 s step mean's noise,
measured as the bench measures it) it prints the noncentrality

    d2 = s' (S^-1 - S^-1 X (X' S^-1 X)^-1 X' S^-1) s

of the generalised least-squares test of the warm-up's three amplitudes, summed over the triad
(1, -0.6, 0.8 of the amplitude, as warm_up_run() draws it), and that test's power at a 1e-3
false-alarm rate (chi-square, 3 degrees of freedom, above 16.27; Monte Carlo). s: the warm-up's
mean over each step; S: the step means' covariance (white density^2 / duration, plus the
wander's exact window-averaged covariance: a Gauss-Markov, or a flicker as a sum of
Gauss-Markov processes two per decade, flat in Allan deviation within 4 % from 1 s to 1e5 s);
X: the nuisance columns on a gyro's step means (its bias, and the turn rate about each axis for
its scale and misalignment; with --temperature-polynomial also dT and dT^2, as diagnose's
superset of catalogue terms carries them: with three plateaus they take up each plateau's mean,
so that only the decay's shape within the first plateau and the capture is left to tell it
from them).

Why: diagnose re-estimates the wander from the run itself, and judges a warm-up against it by
BIC (docs/guide-loop.md, "Where a run cannot tell"). With the temperature polynomial this
oracle's power at 5x is 0.56 (MEMS class) and 0.69 (ADIS16488 class) for tau 1800 s without a
capture, 0.88-0.99 in the other cells: "every time" at 5x is beyond any test on this campaign.

The campaign is tests/unit/solver/warm_up_campaign.hpp's, written again here (its step times,
durations and gaps): keep the two in step. The units: sim_run.hpp's mems_gauss_markov_unit()
(the defaults: white 5e-3 deg/s/sqrt(Hz), Gauss-Markov 10 deg/h with a 300 s correlation
time), and the ADIS16488 sheet's (--white 4.33e-3 --flicker-b 7.68: ARW 0.26 deg/sqrt(h), an
Allan floor of 5.1 deg/h).

    warm_up_oracle.py [--white DPS_RTHZ] [--gm-sigma DEG_H] [--gm-tau S] [--flicker-b DEG_H]
                      [--temperature-polynomial]

Needs Debian's python3-numpy.
"""

import argparse

import numpy as np

CHI2_3DOF_1E3 = 16.266  # upper 1e-3 point of chi-square with 3 degrees of freedom


def campaign(capture_s):
    """(start s, duration s, turn axis or None, turn rate deg/s, degC) per recorded step."""
    steps = []
    t = 0.0
    for _ in range(int(capture_s // 60)):  # the capture's 60 s segments (diagnose's noise rows)
        steps.append((t, 60.0, None, 0.0, 25.0))
        t += 60.0
    for temp in (25, -10, 60):
        first = True
        for _outer in range(8):
            for _inner in range(3):
                t += (8.0 if temp == 25 else 1800.0) if first else 10.0
                first = False
                steps.append((t, 60.0, None, 0.0, temp))
                t += 60.0
        for rate in (10.0, 30.0, 100.0, 300.0):
            for sign in (1.0, -1.0):
                for axis in (2, 0, 1):
                    t += 4.0
                    steps.append((t, 720.0 / rate, axis, sign * rate, temp))
                    t += 720.0 / rate
    return steps


def gauss_markov_window_cov(a1, l1, a2, l2, tau_c):
    """Mean over [a1, a1+l1] x [a2, a2+l2] of exp(-|t-s|/tau_c) (unit variance)."""
    def g(x):  # g'' = exp(-|x|/tau_c), g(0) = g'(0) = 0
        return tau_c * tau_c * np.expm1(-np.abs(x) / tau_c) + tau_c * np.abs(x)
    d = a1 - a2
    return (g(d + l1) - g(d + l1 - l2) - g(d) + g(d - l2)) / (l1 * l2)


def flicker_components(b_deg_h):
    """A flicker bias of coefficient B [deg/h] (Allan floor 0.664 B, as sim/noise.hpp makes it)
    as a sum of Gauss-Markov processes, two per decade of correlation time from 0.1 s to 1e7 s,
    of equal variance: flat in Allan deviation within 4 % from 1 s to 1e5 s (measured).
    Returns (sigma deg/s, tau_c s) pairs scaled so that the Allan deviation at 1000 s is the
    floor."""
    taus = 10.0 ** (np.arange(-2, 15) / 2.0)

    def allan_var(tau, sigma2):  # 0.5 E[(mean2 - mean1)^2] of each component, summed
        return sum(sigma2 * (gauss_markov_window_cov(0, tau, 0, tau, tc) -
                             gauss_markov_window_cov(0, tau, tau, tau, tc)) for tc in taus)

    floor = 0.664 * b_deg_h / 3600.0
    sigma2 = floor**2 / allan_var(1000.0, 1.0)
    return [(np.sqrt(sigma2), tc) for tc in taus]


def noncentrality(capture_s, tau_s, amplitude, white, wanders, temperature):
    """wanders: (sigma deg/s, tau_c s) of each Gauss-Markov component of the bias."""
    steps = campaign(capture_s)
    n = len(steps)
    start = np.array([s[0] for s in steps])
    length = np.array([s[1] for s in steps])
    a1, a2 = start[:, None], start[None, :]
    l1, l2 = length[:, None], length[None, :]
    cov = np.zeros((n, n))
    for sigma, tau_c in wanders:
        cov += sigma**2 * gauss_markov_window_cov(a1, l1, a2, l2, tau_c)
    cov[np.diag_indices(n)] += white**2 / length
    signal = amplitude * tau_s * (np.exp(-start / tau_s) - np.exp(-(start + length) / tau_s)) / length
    columns = [np.ones(n)]
    for axis in range(3):
        columns.append(np.array([r if ax == axis else 0.0 for (_, _, ax, r, _) in steps]))
    if temperature:
        dt = np.array([step[4] - 25.0 for step in steps])
        columns += [dt, dt * dt]
    x = np.array(columns).T
    inv = np.linalg.inv(cov)
    projected = inv - inv @ x @ np.linalg.solve(x.T @ inv @ x, x.T @ inv)
    return float(signal @ projected @ signal)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--white", type=float, default=5e-3, help="white density [deg/s/sqrt(Hz)]")
    p.add_argument("--gm-sigma", type=float, default=10.0, help="Gauss-Markov sigma [deg/h]")
    p.add_argument("--gm-tau", type=float, default=300.0, help="its correlation time [s]")
    p.add_argument("--flicker-b", type=float, default=0.0,
                   help="a flicker bias of this coefficient B [deg/h] instead of the "
                        "Gauss-Markov (ADIS16488 class: --white 4.33e-3 --flicker-b 7.68)")
    p.add_argument("--temperature-polynomial", action="store_true",
                   help="dT and dT^2 among the nuisance columns")
    a = p.parse_args()
    wanders = (flicker_components(a.flicker_b) if a.flicker_b > 0.0 else
               [(a.gm_sigma / 3600.0, a.gm_tau)])
    # As the bench measures it (warm_up_campaign.hpp, step_mean_noise_dps): the expected sample
    # standard deviation of the 180 consecutive 60 s means of three hours at rest.
    start = 60.0 * np.arange(180)
    means = sum(s**2 * gauss_markov_window_cov(start[:, None], 60.0, start[None, :], 60.0, tc)
                for s, tc in wanders) + np.eye(180) * a.white**2 / 60.0
    step_noise = np.sqrt((np.trace(means) - means.sum() / 180.0) / 179.0)
    print(f"a 60 s step mean's noise: {step_noise:.5f} deg/s")
    z = np.random.default_rng(1).standard_normal((200000, 3))
    triad = 1.0 + 0.6**2 + 0.8**2
    for capture in (0.0, 1800.0):
        for tau in (300.0, 900.0, 1800.0):
            for times in (5, 10, 20):
                d2 = triad * noncentrality(capture, tau, times * step_noise, a.white, wanders,
                                           a.temperature_polynomial)
                shifted = z.copy()
                shifted[:, 0] += np.sqrt(d2)
                power = float(((shifted**2).sum(axis=1) > CHI2_3DOF_1E3).mean())
                print(f"capture {capture:5.0f} s tau {tau:5.0f} s {times:3d}x: d2 {d2:7.1f}, "
                      f"power at 1e-3 {power:.2f}")


if __name__ == "__main__":
    main()
