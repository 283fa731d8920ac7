"""Cost of fitting the isolation system to a building record, against a solve_ivp least-squares fit (issue 10).

Run: python benchmarks/bench_building_fit.py [--repeat N] [--no-baseline]

The record: 60 s at 200 Hz (2 s at the pushed state, then the release at t = 2.137 s), three channels of
the isolation layer (displacement x with noise 0.2 mm, velocity v with 1 mm/s, acceleration a with 0.02
m/s^2 and a sensor zero of 0.01 m/s^2), made by the independent event-located solve_ivp of
``tests/building_reference.py``; the release instant is not given to the fit. Timed (best of ``--repeat``):

* ``fit_isolation(channels, mass)`` of the linear + Coulomb model from its own start (decay analysis,
  detected release): what a user runs;
* the baseline on the same data from the same start (the package's own: decay analysis, detected release,
  the quiet segment's levels): scipy ``least_squares`` (bounds, ``x_scale="jac"``,
  otherwise its defaults) whose residual integrates the equation of motion with ``solve_ivp`` (DOP853,
  rtol 1e-10, atol 1e-12 m, terminal events at the reversals, where the sliders stick or the motion turns)
  for every model evaluation; timed once (it is slow), in the same run;
* the bilinear model (rubber k1 = 40 MN/m, k2 = 4 MN/m, F_y = 80 kN, with sliders) on its own 60 s record,
  from design start values 15-25% off the truth (timed once).

Printed: seconds, model evaluations, the speed-up against the baseline, and how far the baseline's
estimates lie from the package's in the package's standard errors (they fit the same model: near 0).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares

sys.path.insert(0, str(Path(__file__).parent.parent / "tests"))
from building_reference import reference  # noqa: E402

import quickrelease.building.isolation_fit as IF  # noqa: E402
from quickrelease.building.isolation_fit import BuildingChannel, fit_isolation  # noqa: E402

M = 4.0e5  # kg
RATE, PRE, DURATION, RELEASE = 200.0, 2.0, 60.0, 2.137
NOISE = {"x": 2e-4, "v": 1e-3, "a": 0.02}
LINEAR = {"period": 2.0, "damping_ratio": 0.03, "friction": 8.0e3, "d0": 0.15}
BILINEAR = {"k1": 4.0e7, "k2": 4.0e6, "Fy": 8.0e4, "damping_ratio": 0.03, "friction": 8.0e3, "d0": 0.2}


def record(k1, k2, fp, c, Fs, d0, seed=1) -> list[BuildingChannel]:
    """The three channels (x, v, a) of the isolation layer from the independent solve_ivp reference."""
    rng = np.random.default_rng(seed)
    t = np.arange(round(DURATION * RATE)) / RATE
    rows = reference(M, k1, k2, fp, c, Fs, d0, t - RELEASE, with_rates=True)[0]
    offsets = {"x": 0.0, "v": 0.0, "a": 0.01}
    return [BuildingChannel(kind, kind, t, y + offsets[kind] + rng.normal(0.0, NOISE[kind], t.size))
            for kind, y in zip("xva", rows, strict=True)]


def ivp_states(T, zeta, Fs, d0, t):
    """x, v, a of the linear + Coulomb layer at times t after the release (sorted), by solve_ivp with events."""
    k = M * (2.0 * math.pi / T) ** 2
    c = 2.0 * zeta * math.sqrt(k * M)
    out = np.zeros((3, t.size))
    out[0] = d0
    t_end = float(t[-1])
    tt, x, v = 0.0, d0, 0.0
    if abs(k * d0) <= Fs or t_end <= 0.0:
        return out
    direction = -math.copysign(1.0, k * d0)
    while tt < t_end:
        def rhs(_t, s, direction=direction):
            return [s[1], -(c * s[1] + k * s[0] + Fs * direction) / M]

        def reversal(_t, s):
            return s[1]

        reversal.terminal, reversal.direction = True, -direction
        sol = solve_ivp(rhs, (tt, t_end), [x, v], method="DOP853", rtol=1e-10, atol=1e-12, events=reversal,
                        dense_output=True)
        seg = (t >= tt) & (t <= sol.t[-1])
        xs, vs = sol.sol(t[seg])
        out[:, seg] = xs, vs, -(c * vs + k * xs + Fs * direction) / M
        if sol.status != 1:
            break
        tt, x, v = float(sol.t[-1]), float(sol.y[0, -1]), 0.0
        if abs(k * x) <= Fs:  # the sliders hold it
            out[:, t > tt] = [[x], [0.0], [0.0]]
            break
        direction = -math.copysign(1.0, k * x)
    return out


def baseline_fit(channels, x0):
    """scipy least_squares whose residual calls solve_ivp for every model evaluation."""
    t = channels[0].t
    data = np.concatenate([ch.values for ch in channels])
    sig = np.concatenate([np.full(ch.t.size, NOISE[ch.kind]) for ch in channels])
    nfev = [0]

    def residual(theta):
        T, zeta, Fs, d0, t_r, ox, ov, oa = theta
        nfev[0] += 1
        x, v, a = ivp_states(T, zeta, Fs, d0, t - t_r)
        return (np.concatenate([x + ox, v + ov, a + oa]) - data) / sig

    lo = [1e-3, 0.0, 0.0, -np.inf, x0[4] - 0.25, -np.inf, -np.inf, -np.inf]
    hi = [1e3, 0.95, np.inf, np.inf, x0[4] + 0.25, np.inf, np.inf, np.inf]
    res = least_squares(residual, x0, bounds=(lo, hi), x_scale="jac")
    return res, nfev[0]


def timed(func, repeat):
    best, out = math.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = func()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=3, help="best of N for the package's fits")
    parser.add_argument("--no-baseline", action="store_true", help="skip the (slow) solve_ivp baseline")
    args = parser.parse_args()
    p = LINEAR
    k = M * (2.0 * math.pi / p["period"]) ** 2
    c = 2.0 * p["damping_ratio"] * math.sqrt(k * M)
    channels = record(k, k, math.inf, c, p["friction"], p["d0"])
    n = sum(ch.t.size for ch in channels)
    print(f"record: {DURATION:.0f} s at {RATE:.0f} Hz, channels {', '.join(ch.name for ch in channels)} ({n} samples)")
    rows = []
    own, fit = timed(lambda: fit_isolation(channels, M, "linear"), args.repeat)
    rows.append(("linear + Coulomb, own start", own, fit.nfev))
    # the same start for the baseline: the package's own (decay analysis, detected release, quiet-segment
    # levels), which the fit above started from
    t_r0 = IF._detect_release(channels)
    noise = {ch.name: IF._quiet_noise(ch, t_r0) for ch in channels}
    pre = channels[0].values[channels[0].t < t_r0]
    start = {**IF._start("linear", M, channels, t_r0, float(np.median(pre)), noise), "d0": float(np.median(pre)),
             "offset_x": 0.0, **{f"offset_{ch.name}": float(np.median(ch.values[ch.t < t_r0])) for ch in channels[1:]}}
    truth = {"period": p["period"], "damping_ratio": p["damping_ratio"], "friction": p["friction"], "d0": p["d0"],
             "release_time": RELEASE}
    base = None
    if not args.no_baseline:
        names = ["period", "damping_ratio", "friction", "d0", "release_time", "offset_x", "offset_v", "offset_a"]
        x0 = [start[nm] if nm != "release_time" else t_r0 for nm in names]
        base, (res, nfev) = timed(lambda: baseline_fit(channels, x0), 1)
        rows.append(("baseline: least_squares + solve_ivp, same start", base, nfev))
    b = BILINEAR
    fp = b["Fy"] * (1.0 - b["k2"] / b["k1"])
    cb = 2.0 * b["damping_ratio"] * math.sqrt(b["k1"] * M)
    bil = record(b["k1"], b["k2"], fp, cb, b["friction"], b["d0"], seed=2)
    T1 = 2.0 * math.pi * math.sqrt(M / b["k1"])
    design = {"period": 1.15 * T1, "damping_ratio": 0.75 * b["damping_ratio"], "friction": 0.8 * b["friction"],
              "stiffness_ratio": 1.2 * b["k2"] / b["k1"], "yield_force": 0.8 * b["Fy"]}
    bt, bfit = timed(lambda: fit_isolation(bil, M, "bilinear", start=design), 1)
    rows.append(("bilinear + Coulomb, design start", bt, bfit.nfev))
    print(f"{'task':52s} {'seconds':>8s} {'model evals':>12s} {'baseline / this':>16s}")
    for what, seconds, evals in rows:
        ratio = f"{base / seconds:15.1f}x" if base else ""
        print(f"{what:52s} {seconds:8.3f} {evals:12d} {ratio:>16s}")
    print("linear estimates (truth) and the fit's 95% interval:")
    for nm, value in truth.items():
        lo, hi = fit.ci95[nm]
        print(f"  {nm:14s} {fit.estimates[nm]:.6g} ({value:.6g}) [{lo:.6g}, {hi:.6g}]")
    if base:
        dz = [(res.x[i] - fit.estimates[nm]) / fit.std_errors[nm] for i, nm in enumerate(names)]
        print("baseline - package, in the package's standard errors: "
              + ", ".join(f"{nm} {z:.2g}" for nm, z in zip(names, dz, strict=True)))
    btruth = {"period": T1, "stiffness_ratio": b["k2"] / b["k1"], "yield_force": b["Fy"],
              "damping_ratio": b["damping_ratio"], "friction": b["friction"]}
    print("bilinear estimates (truth): " + ", ".join(f"{nm} {bfit.estimates[nm]:.5g} ({v:.5g})"
                                                   for nm, v in btruth.items()))


if __name__ == "__main__":
    main()
