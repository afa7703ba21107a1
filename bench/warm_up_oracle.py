#!/usr/bin/python3
"""What the best possible test could find of issue 28's gyro warm-up on a MEMS-class unit: the
oracle that knows the noise (white and Gauss-Markov, their true parameters) and the warm-up's time
constant. For each cell of calstand_warm_up_detection_bench (static capture 0 or 1800 s, tau 300,
900, 1800 s, amplitude 5, 10, 20 times a 60 s step mean's noise) it prints the noncentrality

    d2 = s' (S^-1 - S^-1 X (X' S^-1 X)^-1 X' S^-1) s

of the generalised least-squares test of the warm-up's three amplitudes, summed over the triad
(1, -0.6, 0.8 of the amplitude, as warm_up_run() draws it), and that test's power at a 1e-3
false-alarm rate (chi-square, 3 degrees of freedom, above 16.27; Monte Carlo). s: the warm-up's
mean over each step; S: the step means' covariance (white density^2 / duration, plus the
Gauss-Markov's exact window-averaged covariance); X: the nuisance columns on a gyro's step means
(its bias, and the turn rate about each axis for its scale and misalignment; with
--temperature-polynomial also dT and dT^2, as diagnose's superset of catalogue terms carries them:
with three plateaus they take up each plateau's mean, so that only the decay's shape within the
first plateau and the capture is left to tell it from them).

Why: diagnose re-estimates the wander from the run itself, and its 2 ln LR on 5x warm-ups is
15-47 (median about 26). This oracle's d2 is 36-67 on the bias and turn columns, 16-39 with the
temperature polynomial: that part of the gap is what the catalogue's temperature terms take,
the rest what not knowing the noise costs (docs/guide-loop.md, "Where a run cannot tell").

The campaign is tests/unit/solver/warm_up_campaign.hpp's, written again here (its step times,
durations and gaps): keep the two in step. The unit is sim_run.hpp's mems_gauss_markov_unit():
white 5e-3 deg/s/sqrt(Hz), Gauss-Markov 10 deg/h with a 300 s correlation time.

    warm_up_oracle.py [--white DPS_RTHZ] [--gm-sigma DEG_H] [--gm-tau S]
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
        return tau_c * tau_c * np.exp(-abs(x) / tau_c) + tau_c * abs(x) - tau_c * tau_c
    d = a1 - a2
    return (g(d + l1) - g(d + l1 - l2) - g(d) + g(d - l2)) / (l1 * l2)


def noncentrality(capture_s, tau_s, amplitude, white, gm_sigma, gm_tau, temperature):
    steps = campaign(capture_s)
    n = len(steps)
    cov = np.empty((n, n))
    for i, (a1, l1, _, _, _) in enumerate(steps):
        for j, (a2, l2, _, _, _) in enumerate(steps):
            cov[i, j] = gm_sigma**2 * gauss_markov_window_cov(a1, l1, a2, l2, gm_tau)
        cov[i, i] += white**2 / l1
    signal = np.array([amplitude * tau_s * (np.exp(-a / tau_s) - np.exp(-(a + l) / tau_s)) / l
                       for (a, l, _, _, _) in steps])
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
    p.add_argument("--temperature-polynomial", action="store_true",
                   help="dT and dT^2 among the nuisance columns")
    a = p.parse_args()
    sigma = a.gm_sigma / 3600.0
    step_noise = np.sqrt(sigma**2 * gauss_markov_window_cov(0, 60, 0, 60, a.gm_tau) +
                         a.white**2 / 60.0)
    print(f"a 60 s step mean's noise: {step_noise:.5f} deg/s")
    z = np.random.default_rng(1).standard_normal((200000, 3))
    triad = 1.0 + 0.6**2 + 0.8**2
    for capture in (0.0, 1800.0):
        for tau in (300.0, 900.0, 1800.0):
            for times in (5, 10, 20):
                d2 = triad * noncentrality(capture, tau, times * step_noise, a.white, sigma,
                                           a.gm_tau, a.temperature_polynomial)
                shifted = z.copy()
                shifted[:, 0] += np.sqrt(d2)
                power = float(((shifted**2).sum(axis=1) > CHI2_3DOF_1E3).mean())
                print(f"capture {capture:5.0f} s tau {tau:5.0f} s {times:3d}x: d2 {d2:7.1f}, "
                      f"power at 1e-3 {power:.2f}")


if __name__ == "__main__":
    main()
