"""Cost of the building's fit with its global stage, against the fit of an earlier commit, in the same run.

Run: python benchmarks/bench_building_global.py [--baseline COMMIT] [--repeat N] [--no-baseline]

The records: 60 s at 200 Hz, three channels of the isolation layer (x with 0.2 mm noise and a 2 mm zero, v
with 1 mm/s, a with 0.02 m/s^2 and a 0.01 m/s^2 zero; the 2dof record: x, a and the roof's acceleration),
made by the independent event-located solve_ivp of ``tests/building_reference.py``; the release instant is
not given. Timed by process CPU time (one core; the fit holds BLAS to one thread), best of ``--repeat``:

* ``fit_isolation`` of the linear, bilinear and 2dof models with no design values (the global stage: the
  record's starts and the CMA-ES runs, then the polish and the intervals);
* ``analyse_building(compare=True)`` of the linear record (the three models fitted: ``--compare``);
* the same calls in a subprocess on the package of ``--baseline`` (default 412f6e4, the fit before the
  global stage), checked out into a temporary git worktree: the ratio new / baseline.

Printed: CPU seconds, the target of each (linear 1 s, bilinear 5 s, 2dof 10 s, compare 15 s), the ratio to
the baseline, and each fit's delta chi-square against the baseline's and its certificate.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

M, MS = 8.0e5, 5.0e5
RATE, DURATION, RELEASE = 200.0, 60.0, 2.0137
NOISE = {"x": 2e-4, "v": 1e-3, "a": 0.02, "a_roof": 0.02}
TARGETS = {"linear": 1.0, "bilinear": 5.0, "2dof": 10.0, "compare": 15.0}


def records() -> dict[str, dict[str, tuple[np.ndarray, np.ndarray]]]:
    """The three records: channel name -> (t, values), from the independent reference."""
    from building_reference import reference, reference_2dof

    rng = np.random.default_rng(7)
    t = np.arange(round(DURATION * RATE)) / RATE
    out = {}
    k = M * (2 * math.pi / 2.5) ** 2
    rows = reference(M, k, k, math.inf, 2 * 0.05 * math.sqrt(k * M), 0.008 * M * 9.81, 0.15, t - RELEASE,
                     with_rates=True)[0]
    out["linear"] = {n: (t, y + {"x": 0.002, "v": 0.0, "a": 0.01}[n] + rng.normal(0, NOISE[n], t.size))
                     for n, y in zip("xva", rows, strict=True)}
    k1 = M * (2 * math.pi / 1.1) ** 2
    rows = reference(M, k1, 0.12 * k1, 0.06 * M * 9.81 * 0.88, 2 * 0.02 * math.sqrt(k1 * M), 0.01 * M * 9.81,
                     0.16, t - RELEASE, with_rates=True)[0]
    out["bilinear"] = {n: (t, y + {"x": 0.002, "v": 0.0, "a": 0.01}[n] + rng.normal(0, NOISE[n], t.size))
                       for n, y in zip("xva", rows, strict=True)}
    kb = M * (2 * math.pi / 2.5) ** 2
    ks = MS * (2 * math.pi / 0.4) ** 2
    r2, _ = reference_2dof(M, MS, kb, 2 * 0.05 * math.sqrt(kb * M), ks, 2 * 0.02 * math.sqrt(ks * MS),
                           0.006 * M * 9.81, 0.15, t - RELEASE)
    out["2dof"] = {"x": (t, r2["xb"] + 0.002 + rng.normal(0, NOISE["x"], t.size)),
                   "a": (t, r2["ab"] + 0.01 + rng.normal(0, NOISE["a"], t.size)),
                   "a_roof": (t, r2["as"] + rng.normal(0, NOISE["a_roof"], t.size))}
    return out


def run(data_file: str, repeat: int) -> dict:
    """Time the fits of the records in ``data_file`` with the package on sys.path (this one or a baseline's)."""
    from quickrelease.building.isolation_fit import BuildingChannel, fit_isolation
    from quickrelease.studies.building_analysis import analyse_building

    data = np.load(data_file)
    recs: dict[str, dict] = {}
    for key in data.files:
        model, name, what = key.split("|")
        recs.setdefault(model, {}).setdefault(name, {})[what] = data[key]
    out = {}
    for model, chans in recs.items():
        channels = [BuildingChannel(n, n, c["t"], c["y"]) for n, c in chans.items()]
        kw = {"superstructure_mass": MS} if model == "2dof" else {}
        best, fit = math.inf, None
        for _ in range(repeat):
            t0 = time.process_time()
            fit = fit_isolation(channels, M, model, **kw)
            best = min(best, time.process_time() - t0)
        search = getattr(fit, "search", None)
        out[model] = {"cpu_s": best, "chi2": fit.chi2, "period": fit.estimates["period"],
                      "confirmed": None if search is None else bool(search.global_minimum_confirmed),
                      "reached": None if search is None else f"{search.reached_best}/{search.starts}"}
        if model == "linear":
            t0 = time.process_time()
            analyse_building(channels=channels, mass=M, model="linear", compare=True, superstructure_mass=MS)
            out["compare"] = {"cpu_s": time.process_time() - t0}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", default="412f6e4", help="commit whose fit is the baseline (default 412f6e4)")
    ap.add_argument("--repeat", type=int, default=1, help="timed fits per model (best of; default 1)")
    ap.add_argument("--no-baseline", action="store_true", help="skip the baseline")
    ap.add_argument("--_child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args._child:  # a baseline's timing, in its own interpreter
        print(json.dumps(run(args._child, args.repeat)))
        return
    with tempfile.TemporaryDirectory() as tmp:
        data_file = os.path.join(tmp, "records.npz")
        arrays = {f"{m}|{n}|{w}": v for m, ch in records().items() for n, (t, y) in ch.items()
                  for w, v in (("t", t), ("y", y))}
        np.savez(data_file, **arrays)
        new = run(data_file, args.repeat)
        base = None
        if not args.no_baseline:
            tree = os.path.join(tmp, "baseline")
            subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", tree, args.baseline],
                           check=True)
            try:
                env = {**os.environ, "PYTHONPATH": os.path.join(tree, "src")}
                done = subprocess.run([sys.executable, __file__, "--_child", data_file, "--repeat", str(args.repeat)],
                                      env=env, capture_output=True, text=True, check=True)
                base = json.loads(done.stdout.strip().splitlines()[-1])
            finally:
                subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", tree], check=False)
    print(f"building fit with the global stage: 60 s, 200 Hz, 3 channels; CPU seconds, one core "
          f"(baseline {args.baseline if base else 'not run'})")
    print(f"{'fit':10} {'new [s]':>8} {'target':>7} {'met':>4} {'base [s]':>9} {'ratio':>6} {'dchi2 vs base':>14} "
          f"{'certificate':>12}")
    for key in ("linear", "bilinear", "2dof", "compare"):
        n = new[key]
        b = base.get(key) if base else None
        ratio = f"{n['cpu_s'] / b['cpu_s']:.2f}" if b else "-"
        dchi = f"{n['chi2'] - b['chi2']:+.2f}" if b and "chi2" in n else "-"
        cert = f"{'yes' if n.get('confirmed') else 'NO'} {n.get('reached')}" if "confirmed" in n else ""
        print(f"{key:10} {n['cpu_s']:8.2f} {TARGETS[key]:7.0f} {'yes' if n['cpu_s'] < TARGETS[key] else 'no':>4} "
              f"{b['cpu_s'] if b else math.nan:9.2f} {ratio:>6} {dchi:>14} {cert:>12}")


if __name__ == "__main__":
    main()
