"""Cost of the fits of the isolation systems without a closed form (issue 24), against the linear fit, same run.

Run: python benchmarks/bench_isolators.py [--repeat N] [--models pendulum,boucwen,boucwen-weak,power,boucwen-damper]
[--seeds 11,12,13] [--truth]

The records: 60 s at 200 Hz after 2 s of rest, three channels of the isolation layer (x with 0.2 mm noise and
a 2 mm zero, v with 1 mm/s, a with 0.02 m/s^2 and a 0.01 m/s^2 zero), made by the independent solve_ivp
simulator of ``tests/building/isolator_reference.py`` (not the package's integrator); the release instant
is not given, no design values:

* ``pendulum``: 1000 t on curved surface sliders R = 3 m, mu 0.01 / 0.025, a = 40 s/m, d0 = 0.30 m;
* ``boucwen``: 800 t on lead-rubber bearings Kd = 3.5 MN/m (post-yield period 3.0 s), Qd = 400 kN (5 % of W),
  dy = 25 mm, n = 1, zeta 2 %, d0 = 0.20 m (it rings down for the whole record: no sliders);
* ``boucwen-weak``: the same with Kd = 1.6 MN/m (4.4 s): Kd d0 = 320 kN falls short of Qd, so the layer barely
  recentres (one swing to 0.07 m, then a creep towards 0.04 m over the minute), a test pushed short of the
  bearings' restoring range; the hard case (not part of the default run): its global minimum was found by no
  start until the Bouc-Wen fit started from the measured loop (``building.boucwen_loop``, 2026-11-27); chi2_red
  the noise's, the minimum reached by the loop's start alone ("not confirmed");
* ``power``: 800 t, linear bearings T = 2.5 s with sliders (0.8 % of W) and fluid dampers C = 300 kN at 1 m/s,
  alpha = 0.4, d0 = 0.15 m;
* ``boucwen-damper``: the ``boucwen`` bearings with fluid viscous dampers instead of the 2 % damping, C = 300 kN
  at 1 m/s, alpha = 0.4 (fitted with ``damping="power"``: damping_coefficient and damping_exponent); after 2.5 s
  and seven turns the layer creeps back for the rest of the minute on the dampers' slow manifold. It cost 17-22 s
  (seeds 1-3) while the creep was integrated on explicit steps of the dampers' relaxation time until that was 100
  times the swing's (3 600 grid points a minute, 4.5 ms); on the slow manifold from 30 times, with two corrections
  for inertia and steps of its own slow time (466 points, 0.95 ms), 8.9-10.0 s (2026-11-27, paired with the old
  tree, load ~2), each seed at the chi-square it had;
* the baseline: the linear model's fit of a linear record of the same length (viscous 5 %, sliders 0.8 %).

Measured 2026-11-27 (fourth session; paired runs, the session's base 0b1e3bb and main alternated, --repeat 2, load
1.5-2 on 2 cores): pendulum 3.3 -> 3.6-3.7 s (four more starts: Constantinou's law at four ratios mu_slow /
mu_fast, which found the truth's basin on 3 of 11 seeds where every start had missed it), boucwen 11.0-11.3 ->
7.8 s, power 2.6-2.7 -> 2.3-2.5 s, boucwen-weak 15.5-16.6 -> 12.1 s; chi2_red and the certificates unchanged.

Measured 2026-11-27 (seventh session, seed 11, paired with the session's base e81088f, load ~1.7 on 2 cores), after
the solver's steps were measured against each parameter's own magnitude (scipy's ``xtol`` had read the dampers'
coefficient as the scale of every step) and the sliders' face was tried: pendulum 4.1 -> 3.5 s, boucwen 10.6 -> 10.9
s, power 1.5 -> 1.7 s, boucwen-damper 9.0 -> 9.1 s ("not confirmed" -> confirmed; seeds 1 and 3 likewise, 10.3 and
12.1 s), boucwen-weak 9.7 -> 15.9 s (12.8 s alone; "not confirmed" -> confirmed: the record's, the loop's and the
bilinear fit's starts now reach its minimum); every chi-square the truth-started fit's, as before.

Measured 2026-11-28 (eighth session, seed 11, paired with the session's base 1eb24a7, load ~1 on 2 cores), after
the Bouc-Wen fit's bilinear start was fitted as a start (its best basin alone on the whole record, no polish) and
the misfit's evaluations lost overhead (bit for bit the same): pendulum 3.39 -> 3.17 s, boucwen 8.08 -> 7.44 s,
power 1.77 -> 1.72 s, boucwen-damper 8.96 -> 8.42 s, boucwen-weak 11.86 -> 9.54 s; every chi-square as before, each
confirmed. Seeds 1-4 (without the profile intervals): boucwen-weak 7.6, 8.6, 10.7, 8.9 s, boucwen-damper 6.9, 8.9,
9.4, 7.4 s.

Timed by process CPU time (one core), best of ``--repeat``. Printed: CPU seconds, the issue's target (10 s),
the ratio to the baseline, the reduced chi-square and whether the global minimum was confirmed. ``--seeds``:
the records' noise seeds (one row each); ``--truth``: each record also fitted from the true parameters alone
(``start=truth, global_search=False``), and the auto fit's chi2 above that fit's printed (it found the
minimum where that is below 1).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests" / "building"))

RATE, DURATION, RELEASE = 200.0, 60.0, 2.0137
NOISE = {"x": 2e-4, "v": 1e-3, "a": 0.02}
ZERO = {"x": 0.002, "v": 0.0, "a": 0.01}
TARGET = 10.0


def systems():
    import isolator_reference as ref

    k = 8e5 * (2 * math.pi / 2.5) ** 2
    return {
        "linear": ("linear", "viscous", 8e5, ref.linear(8e5, k, 2 * 0.05 * math.sqrt(k * 8e5), friction=0.008 * 8e5 *
                                                         9.80665), 0.15),
        "pendulum": ("pendulum", "viscous", 1e6, ref.pendulum(1e6, 3.0, 0.01, 0.025, 40.0), 0.30),
        "boucwen": ("boucwen", "viscous", 8e5, ref.boucwen(8e5, 3.5e6, 4e5, 0.025, 1.0,
                                                           damping=2 * 0.02 * math.sqrt(3.5e6 * 8e5)), 0.20),
        "boucwen-weak": ("boucwen", "viscous", 8e5, ref.boucwen(8e5, 1.6e6, 4e5, 0.025, 1.0,
                                                                damping=2 * 0.02 * math.sqrt(1.6e6 * 8e5)), 0.20),
        "power": ("linear", "power", 8e5, ref.linear(8e5, k, 3e5, 0.4, friction=0.008 * 8e5 * 9.80665), 0.15),
        "boucwen-damper": ("boucwen", "power", 8e5, ref.boucwen(8e5, 3.5e6, 4e5, 0.025, 1.0, damping=3e5,
                                                                  damping_exponent=0.4), 0.20),
    }


def truth(system, d0: float) -> dict[str, float]:
    """The record's true parameters, by the fit's names (the physical ones of its model and damper's law, d0,
    the release and the sensors' zeros)."""
    p = system.params
    out = {"d0": d0, "release_time": RELEASE, "offset_x": ZERO["x"], "offset_v": ZERO["v"], "offset_a": ZERO["a"]}
    if system.kind == "boucwen":
        k = p["Kd"]
        out.update(period=2.0 * math.pi * math.sqrt(system.mass / k), characteristic_strength=p["Qd"],
                   yield_displacement=p["dy"], shape=p["n"], friction=p["Fs"])
    elif system.kind == "linear":
        k = p["k"]
        out.update(period=2.0 * math.pi * math.sqrt(system.mass / k), friction=p["Fs"])
    else:
        raise NotImplementedError(f"--truth: {system.kind}")
    if system.exponent != 1.0:
        out.update(damping_coefficient=system.damping, damping_exponent=system.exponent)
    else:
        out["damping_ratio"] = system.damping / (2.0 * math.sqrt(k * system.mass))
    return out


def record(system, d0: float, seed: int):
    import isolator_reference as ref

    from quickrelease.building.isolation_fit import BuildingChannel

    rng = np.random.default_rng(seed)
    t = np.arange(round((DURATION + 2.0) * RATE)) / RATE
    m = ref.simulate(system, d0, t - RELEASE, t_end=DURATION + 1.0)
    return [BuildingChannel(n, n, t, y + ZERO[n] + rng.normal(0.0, NOISE[n], t.size))
            for n, y in (("x", m.x), ("v", m.v), ("a", m.a))]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--models", default="pendulum,boucwen,power,boucwen-damper")
    parser.add_argument("--seeds", default="11")
    parser.add_argument("--truth", action="store_true")
    args = parser.parse_args()
    from threadpoolctl import threadpool_limits

    from quickrelease.building.isolation_fit import fit_isolation

    cases = systems()
    rows = []
    with threadpool_limits(1):
        for name in ["linear", *args.models.split(",")]:
            model, damping, mass, system, d0 = cases[name]
            for seed in [int(s) for s in args.seeds.split(",")] if name != "linear" else [11]:
                channels = record(system, d0, seed=seed)
                best, fit = math.inf, None
                for _ in range(args.repeat):
                    t0 = time.process_time()
                    fit = fit_isolation(channels, mass, model, damping=damping)
                    best = min(best, time.process_time() - t0)
                rows.append((name, best, fit.chi2_reduced, fit.global_minimum_confirmed))
                if len(rows) == 1:
                    print(f"{'record':14s} {'seed':>4s} {'CPU s':>8s} {'target':>7s} {'x linear':>9s} "
                          f"{'chi2_red':>9s}  global minimum")
                cpu, base = best, rows[0][1]
                target = f"{TARGET:g} s" if name != "linear" else "-"
                line = (f"{name:14s} {seed:4d} {cpu:8.2f} {target:>7s} {cpu / base:9.1f} {fit.chi2_reduced:9.3f}  "
                        f"{'confirmed' if fit.global_minimum_confirmed else 'not confirmed'}")
                if args.truth and name != "linear":
                    t0 = time.process_time()
                    ref_fit = fit_isolation(channels, mass, model, damping=damping, start=truth(system, d0),
                                            global_search=False)
                    line += (f"; from the truth: chi2 {ref_fit.chi2:.2f} ({time.process_time() - t0:.1f} s), "
                             f"the auto fit's {fit.chi2 - ref_fit.chi2:+.3f} above it")
                print(line, flush=True)


if __name__ == "__main__":
    main()
