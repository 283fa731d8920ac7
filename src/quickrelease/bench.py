"""Benchmarks of the batch kernels against scipy, measured in the same run (``quickrelease bench``).

* Throughput on one core (the process is pinned to one CPU while measuring): cases per second of the
  stop-time kernel (:func:`batch.stop_time`) and of the identification kernel (:func:`batch.identify`)
  on random cases of the valid parameter space (:func:`sampling.random_releases`, 15% reaching the
  geometric limit).
* The same work done the ordinary way, per case, on a sample: scipy ``solve_ivp`` (DOP853, rtol 1e-10,
  atol 1e-12, terminal events at alpha_dot = 0 and alpha = pi/2) for the stop time; scipy ``quad`` of
  Eq. 10 inside ``brentq`` on F1 for the identification. Speed-ups are per case.
* Accuracy of each against mpmath references (:mod:`reference`, 30 digits) on the same cases: relative
  error of t_F; for the identification, the error of F1 and F2 relative to their bounds F1*, F2*
  (the natural scale: F1 may be near zero).
* ``uq`` with 1e8 samples on a LocalCluster of two Dask workers: wall time and peak memory of the whole
  process tree (skipped with ``quick``).
"""

from __future__ import annotations

import math
import os
import time
from contextlib import contextmanager
from typing import Any

import numpy as np

from . import batch
from .reference import identify_mp, stop_time_mp
from .sampling import random_releases

__all__ = ["run_bench"]


@contextmanager
def _one_core():
    if not hasattr(os, "sched_getaffinity"):
        yield
        return
    old = os.sched_getaffinity(0)
    os.sched_setaffinity(0, {min(old)})
    try:
        yield
    finally:
        os.sched_setaffinity(0, old)


def _rate(func, n: int, repeat: int = 3) -> float:
    func()  # warm up (compilation, caches)
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - t0)
    return n / best


def _solve_ivp_stop(E_S, alpha0, F1, F2, k, m2, L1) -> float:
    from scipy.integrate import solve_ivp

    q = 1.0 / (m2 * L1)

    def rhs(_t, y):
        s, c = math.sin(y[0]), math.cos(y[0])
        d = k + s * s
        return [y[1], -y[1] * y[1] * s * c / d - (2 * F2 * s + F1 * c) * q / d]

    def stop(_t, y):
        return y[1]

    def flat(_t, y):
        return y[0] - 0.5 * math.pi

    stop.terminal, stop.direction = True, -1
    flat.terminal, flat.direction = True, 1
    ad0 = math.sqrt(E_S / (m2 * L1 * L1 * (k + math.sin(alpha0) ** 2)))
    sol = solve_ivp(rhs, (0.0, 1e4), [alpha0, ad0], method="DOP853", rtol=1e-10, atol=1e-12, events=(stop, flat))
    return min(te[0] for te in sol.t_events if te.size)


def _quad_brentq_identify(alpha0, aF, tF, E_S, k, m2, L1) -> tuple[float, float]:
    from scipy.integrate import quad
    from scipy.optimize import brentq

    F1s = E_S / (2 * L1 * (math.sin(aF) - math.sin(alpha0)))
    F2s = E_S / (4 * L1 * (math.cos(alpha0) - math.cos(aF)))

    def t_of(F1):
        F2 = F2s * (1 - F1 / F1s)

        def f(a):
            K = E_S - 2 * F1 * L1 * (math.sin(a) - math.sin(alpha0)) - 4 * F2 * L1 * (math.cos(alpha0) - math.cos(a))
            return math.sqrt(m2 * L1 * L1 * (k + math.sin(a) ** 2) / max(K, 1e-300))

        return quad(f, alpha0, aF, epsabs=0.0, epsrel=1e-12, limit=200)[0] - tF

    F1 = brentq(t_of, 0.0, F1s, xtol=1e-13 * F1s, rtol=1e-14)
    return F1, F2s * (1 - F1 / F1s)


def run_bench(quick: bool = False, seed: int = 0, log=print) -> dict[str, Any]:
    """Run the benchmarks; returns the numbers (the ``--json`` keys). ``log`` receives progress lines."""
    import warnings

    n = 200_000 if quick else 1_000_000
    cases = random_releases(n, seed=seed)
    out: dict[str, Any] = {"cases": n, "quick": quick}
    m = 20 if quick else 60
    sample = random_releases(m, seed=seed + 1)
    ks = sample["c"] * sample["m1"] / sample["m2"]
    args = [(sample["E_S"][i], sample["alpha0"][i], sample["F1"][i], sample["F2"][i], ks[i], sample["m2"][i],
             sample["L1"][i]) for i in range(m)]
    mi = 8 if quick else 20
    ident_sample = random_releases(mi, seed=seed + 2, limit_share=0.0)
    ki = ident_sample["c"] * ident_sample["m1"] / ident_sample["m2"]
    sti = batch.stop_time(**ident_sample)
    iargs = [(ident_sample["alpha0"][i], sti.alpha_final[i], sti.stop_time[i], ident_sample["E_S"][i], ki[i],
              ident_sample["m2"][i], ident_sample["L1"][i]) for i in range(mi)]
    with _one_core():
        out["stop_time_cases_per_s"] = _rate(lambda: batch.stop_time(**cases), n)
        st = batch.stop_time(**cases)
        fr = st.stopped_by == 0
        obs = dict(alpha0=cases["alpha0"][fr], alpha_final=st.alpha_final[fr], stop_time=st.stop_time[fr],
                   E_S=cases["E_S"][fr], c=cases["c"][fr], m1=cases["m1"][fr], m2=cases["m2"][fr], L1=cases["L1"][fr])
        out["identify_cases_per_s"] = _rate(lambda: batch.identify(**obs), int(fr.sum()))
        log(f"kernels: {out['stop_time_cases_per_s']:,.0f} stop times/s, {out['identify_cases_per_s']:,.0f} "
            "identifications/s on one core")
        # the ordinary way, one case at a time, on samples
        t0 = time.perf_counter()
        t_ivp = np.array([_solve_ivp_stop(*a) for a in args])
        per_ivp = (time.perf_counter() - t0) / m
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            t0 = time.perf_counter()
            qb = [_quad_brentq_identify(*a) for a in iargs]
            per_qb = (time.perf_counter() - t0) / mi
    out["solve_ivp_cases_per_s"] = 1.0 / per_ivp
    out["stop_time_speedup_vs_solve_ivp"] = out["stop_time_cases_per_s"] * per_ivp
    out["quad_brentq_cases_per_s"] = 1.0 / per_qb
    out["identify_speedup_vs_quad_brentq"] = out["identify_cases_per_s"] * per_qb
    log(f"scipy, one case at a time: solve_ivp {1 / per_ivp:,.0f} cases/s, quad + brentq {1 / per_qb:,.1f} cases/s")
    # accuracy against mpmath on the same sample cases
    log(f"accuracy vs mpmath: 30-digit references of {len(args)} stop times and {len(iargs)} identifications "
        "(tens of seconds) ...")
    ref = np.array([stop_time_mp(*a)[0] for a in args])
    kern = batch.stop_time(**sample).stop_time
    err_k = np.abs(kern / ref - 1)
    err_ivp = np.abs(t_ivp / ref - 1)
    out.update(stop_time_median_rel_error=float(np.median(err_k)), stop_time_max_rel_error=float(np.max(err_k)),
               solve_ivp_median_rel_error=float(np.median(err_ivp)), solve_ivp_max_rel_error=float(np.max(err_ivp)))
    ident = batch.identify(ident_sample["alpha0"], sti.alpha_final, sti.stop_time, ident_sample["E_S"],
                           ident_sample["c"], ident_sample["m1"], ident_sample["m2"], ident_sample["L1"])
    err_i, err_q = [], []
    for i, a in enumerate(iargs):
        F1, F2 = identify_mp(*a)
        F1s, F2s = ident.F1_max[i], ident.F2_max[i]
        err_i.append(max(abs(ident.F1[i] - F1) / F1s, abs(ident.F2[i] - F2) / F2s))
        err_q.append(max(abs(qb[i][0] - F1) / F1s, abs(qb[i][1] - F2) / F2s))
    out.update(identify_median_rel_error=float(np.median(err_i)), identify_max_rel_error=float(np.max(err_i)),
               quad_brentq_median_rel_error=float(np.median(err_q)), quad_brentq_max_rel_error=float(np.max(err_q)),
               accuracy_cases_stop_time=m, accuracy_cases_identify=mi)
    log(f"accuracy vs mpmath: kernel t_F median {out['stop_time_median_rel_error']:.1e} max "
        f"{out['stop_time_max_rel_error']:.1e}; identification median {out['identify_median_rel_error']:.1e} max "
        f"{out['identify_max_rel_error']:.1e}")
    if not quick:
        out.update(_uq_dask_1e8(log))
    return out


def _uq_dask_1e8(log) -> dict[str, Any]:
    """uq with 1e8 samples on two local Dask workers: wall time and peak memory of the process tree."""
    import tempfile
    import threading
    from importlib import resources

    try:
        import psutil  # comes with dask.distributed
    except ImportError:
        return {"uq_dask_skipped": "dask not installed (pip install 'quickrelease[dask]')"}
    from .case import load_case
    from .uq import run_uq

    text = (resources.files("quickrelease") / "data" / "cases" / "uq_paper.toml").read_text()
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "case.toml")
        with open(path, "w") as fh:
            fh.write(text)
        case = load_case(path)
        me = psutil.Process()
        peak = [0]
        stop = threading.Event()

        def watch():
            while not stop.is_set():
                try:
                    procs = [me, *me.children(recursive=True)]
                    peak[0] = max(peak[0], sum(p.memory_info().rss for p in procs if p.is_running()))
                except psutil.Error:
                    pass
                stop.wait(0.2)

        thread = threading.Thread(target=watch, daemon=True)
        thread.start()
        t0 = time.perf_counter()
        result = run_uq(case, 100_000_000, seed=0, backend="dask", workers=2, out=os.path.join(tmp, "run"))
        wall = time.perf_counter() - t0
        stop.set()
        thread.join()
    log(f"uq 1e8 samples on 2 Dask workers: {wall:.1f} s, peak memory {peak[0] / 2**30:.2f} GiB")
    return {"uq_dask_samples": 100_000_000, "uq_dask_workers": 2, "uq_dask_wall_s": wall,
            "uq_dask_peak_memory_GiB": peak[0] / 2**30, "uq_dask_F1_p50_N": result.percentiles["F1"]["p50"]}
