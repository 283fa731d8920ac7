"""Benchmarks of the batch kernels on two samples, against scipy and mpmath in the same run (``quickrelease bench``).

For each sample, the *bench sample* (:func:`sampling.random_releases`: typical releases, 15% reaching the geometric
limit) and the *wide sample* (:func:`sampling.wide_releases`: the whole valid space, its hard corners
over-weighted, in the strata of :data:`sampling.WIDE_STRATA`):

* Throughput on one core (the process pinned to one CPU, the kernels on one thread): cases per second of the
  stop-time kernel (:func:`batch.stop_time`) and of the identification kernel (:func:`batch.identify`, on the
  friction stops of the same cases), by the wall clock and by the process's CPU time (they differ when the machine
  is busy).
* On all cores (``threads``, default every core numba may use): the same rates, their ratio to one core, and
  whether the results are the same bytes.
* The same work the ordinary way, one case at a time, on an accuracy set drawn from the same distribution: scipy
  ``solve_ivp`` (DOP853, rtol 1e-10, atol 1e-12, terminal events at alpha_dot = 0 and alpha = pi/2) for the stop
  time; ``quad`` of Eq. 10 inside ``brentq`` on F1 for the identification. Speed-ups are per case.
* Accuracy of each against the 30-digit mpmath references (:mod:`reference`) on the accuracy set: relative error
  of t_F; for the identification the error of F1 and F2 relative to their bounds F1*, F2* (the natural scale: F1
  may be near zero). Median and worst; on the wide sample per stratum too (the accuracy set draws the same number
  of cases from each stratum; the sample's median weighs them by the strata's shares), with the worst stratum
  named.
* The conditioning of each case of the accuracy set and the error relative to it (the mixed forward/backward
  measure): s_j, how far the exact answer moves (in the error's measure) when input j moves up by one unit in the
  last place, by mpmath (:func:`_stop_sensitivities`, :func:`_identify_sensitivities`); the case's *1-ulp
  condition number* C = sum_j s_j, and its *backward error* err / C in ulps of the inputs, median and worst per
  sample and stratum (the most s_j at the worst case is the *1-ulp input sensitivity*).
* A status line per target (met, not met, not measured). The accuracy target, relative to the
  conditioning: the median error at most 1e-12 and every case's error at most max(1e-10, 4 C), i.e. 1e-10 where
  the case is well conditioned, else a backward error of at most 4 input ulps.
* ``uq`` with 1e8 samples on a LocalCluster of two Dask workers: wall time and peak memory of the whole process
  tree (skipped with ``quick``).
* Where a CUDA GPU is available to CuPy (:func:`quickrelease.batch._gpu.gpu_available`), the GPU backend
  (:mod:`quickrelease.batch._gpu`): throughput of the stop time and of the identification on both samples (on the
  device, the arrays already there, and end to end from host arrays), the device named, and the most relative difference
  from the CPU kernels on the same cases (t_F, alpha_F; F1* and the feasible ends; lambda = F1/F1* over its
  tolerance, 1e-13 plus its rounding floor ``8 eps t_F / (t_hi - t_lo)``). JSON key ``gpu``: None without a GPU
  (one line says so).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import batch
from .._threads import check_threads, max_threads, using_threads
from ..batch.sampling import WIDE_STRATA, random_releases, wide_releases

__all__ = ["run_bench", "Sizes", "QUICK", "FULL", "TARGETS"]

_KEYS = ("E_S", "alpha0", "F1", "F2", "c", "m1", "m2", "L1")


@dataclass(frozen=True)
class Sizes:
    """How much a bench run measures."""

    cases: int
    """Cases of each sample for the kernels' throughput."""
    stop_time: int
    """Accuracy set of the stop time: cases of the bench sample, and of each stratum of the wide sample."""
    identify: int
    """Accuracy set of the identification: the same (friction stops only)."""
    repeat: int = 5
    """Timed runs of each kernel (the best counts). Five for the full run: on this 2-core virtual machine the
    two-thread rate of one best-of-three varied from 1.1x to 2.0x the one-core rate between quiet runs (the host's
    noise: a chunk now and then took three times as long on both threads), the best of five much less."""
    strata_conditioning: bool = True
    """The 1-ulp sensitivity of every stratum's worst case (else only of the sample's worst case)."""
    case_conditioning: bool = True
    """The 1-ulp condition number of every case of the accuracy sets, and with it the backward error in ulps
    (else only of the worst cases and of those whose error exceeds 1e-10, which the accuracy target needs)."""


#: ``quickrelease bench --quick``: about a minute on a quiet 2-core machine.
QUICK = Sizes(cases=100_000, stop_time=10, identify=5, repeat=2, strata_conditioning=False)
#: ``quickrelease bench``: several minutes (the 1e8-sample uq run on Dask and the condition number of every case of
#: the accuracy sets included).
FULL = Sizes(cases=1_000_000, stop_time=60, identify=20, repeat=5, strata_conditioning=True)

#: The targets of the benchmark: (key, text, sample, what, bound); ``what`` names the measured value.
TARGETS: tuple[tuple[str, str, str, str, float], ...] = (
    ("stop_time_rate_bench", "stop time, bench sample, one core >= 1e7 cases/s", "bench", "stop_time.cases_per_s",
     1e7),
    ("stop_time_rate_wide", "stop time, wide sample, one core >= 4e6 cases/s", "wide", "stop_time.cases_per_s", 4e6),
    ("identify_rate_bench", "identification, bench sample, one core >= 2e6 cases/s", "bench",
     "identify.cases_per_s", 2e6),
    ("identify_rate_wide", "identification, wide sample, one core >= 1e6 cases/s", "wide", "identify.cases_per_s",
     1e6),
)
_ACCURACY_MEDIAN, _ACCURACY_WORST, _CORES = 1e-12, 1e-10, 1.8
#: The accuracy target, relative to the conditioning: every case's error at most max(_ACCURACY_WORST, _CONDITIONED x
#: its 1-ulp condition number), i.e. at most 1e-10 or a backward error of at most 4 ulps of the inputs (what rounding
#: the inputs, and the few roundings of the quantities the kernels derive from them, can cause).
_CONDITIONED = 4.0


@contextmanager
def _one_core():
    """Pin the process to one CPU (where the OS allows) and the kernels to one thread."""
    with using_threads(1):
        if not hasattr(os, "sched_getaffinity"):
            yield
            return
        old = os.sched_getaffinity(0)
        os.sched_setaffinity(0, {min(old)})
        try:
            yield
        finally:
            os.sched_setaffinity(0, old)


def _timed(func: Callable[[], Any], n: int, repeat: int) -> tuple[float, float, Any]:
    """(cases/s by the wall clock, cases/s by the process's CPU time, the result): the best of ``repeat`` runs
    after a warm-up (compilation, caches)."""
    result = func()
    wall = cpu = math.inf
    for _ in range(repeat):
        w0, c0 = time.perf_counter(), time.process_time()
        result = func()
        wall, cpu = min(wall, time.perf_counter() - w0), min(cpu, time.process_time() - c0)
    return n / wall, n / max(cpu, 1e-9), result


def _same_bytes(a: batch._Result, b: batch._Result) -> bool:
    da, db = a.to_dict(), b.to_dict()
    return da.keys() == db.keys() and all(np.asarray(da[k]).tobytes() == np.asarray(db[k]).tobytes() for k in da)


def _observations(cases: dict[str, np.ndarray], st: batch.BatchStop) -> dict[str, np.ndarray]:
    """The friction stops of ``cases`` as identification inputs (alpha0, alpha_F, t_F, E_S, c, m1, m2, L1)."""
    fr = st.stopped_by == 0
    return dict(alpha0=cases["alpha0"][fr], alpha_final=st.alpha_final[fr], stop_time=st.stop_time[fr],
                E_S=cases["E_S"][fr], c=cases["c"][fr], m1=cases["m1"][fr], m2=cases["m2"][fr], L1=cases["L1"][fr])


def _throughput(cases: dict[str, np.ndarray], threads: int, repeat: int) -> dict[str, dict[str, Any]]:
    """Kernel rates on one core and on ``threads`` threads, and whether both give the same bytes."""
    n = len(cases["E_S"])
    with _one_core():
        st_wall, st_cpu, st1 = _timed(lambda: batch.stop_time(**cases), n, repeat)
        obs = _observations(cases, st1)
        m = len(obs["E_S"])
        id_wall, id_cpu, id1 = _timed(lambda: batch.identify(**obs), m, repeat)
    with using_threads(threads):
        st_all, st_all_cpu, stn = _timed(lambda: batch.stop_time(**cases), n, repeat)
        id_all, id_all_cpu, idn = _timed(lambda: batch.identify(**obs), m, repeat)
    return {
        "stop_time": {"cases": n, "cases_per_s": st_wall, "cpu_cases_per_s": st_cpu, "all_cores_cases_per_s": st_all,
                      "all_cores_cpu_cases_per_s": st_all_cpu, "all_cores_ratio": st_all / st_wall,
                      "all_cores_identical": _same_bytes(st1, stn)},
        "identify": {"cases": m, "cases_per_s": id_wall, "cpu_cases_per_s": id_cpu, "all_cores_cases_per_s": id_all,
                     "all_cores_cpu_cases_per_s": id_all_cpu, "all_cores_ratio": id_all / id_wall,
                     "all_cores_identical": _same_bytes(id1, idn), "infeasible": int(np.sum(id1.status != 0))},
    }


# -- the ordinary way: scipy one case at a time ----------------------------------------------------------------

def _solve_ivp_stop(E_S, alpha0, F1, F2, k, m2, L1) -> float:
    """t_F [s] by solve_ivp (DOP853, rtol 1e-10, atol 1e-12) on Eq. 3-4 with terminal events (stop, flat)."""
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
    times = [te[0] for te in sol.t_events if te.size]
    return min(times) if times else math.nan


def _quad_brentq_identify(alpha0, aF, tF, E_S, k, m2, L1) -> tuple[float, float]:
    """(F1, F2) [N] by brentq on F1 in [0, F1*] of quad(Eq. 10) = t_F (epsrel 1e-12)."""
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


# -- accuracy against mpmath ------------------------------------------------------------------------------------

def _strata(sample: str) -> list[tuple[str, float]]:
    return [(name, share) for name, share, _ in WIDE_STRATA] if sample == "wide" else [("bench", 1.0)]


def _accuracy_cases(sample: str, per: int, seed: int, friction_stops: bool) -> tuple[dict[str, np.ndarray], Any]:
    """``per`` cases of the bench sample, or ``per`` of each stratum of the wide sample (fewer where a stratum
    has fewer friction stops, asked for with ``friction_stops``); with their kernel stops."""
    if sample == "bench":
        draw = random_releases(per if not friction_stops else 3 * per, seed=seed,
                               limit_share=0.0 if friction_stops else 0.15)
        draw["stratum"] = np.zeros(len(draw["E_S"]), dtype=int)
    else:
        draw = wide_releases(max(200, int(per / 0.05) * 4), seed=seed, strata=True)
    st = batch.stop_time(**{k: draw[k] for k in _KEYS})
    keep = np.zeros(len(draw["E_S"]), dtype=bool)
    for j in range(len(_strata(sample))):
        ok = (draw["stratum"] == j) & ((st.stopped_by == 0) if friction_stops else (st.stopped_by != 2))
        keep[np.flatnonzero(ok)[:per]] = True
    return {k: v[keep] for k, v in draw.items()}, batch.BatchStop(st.stop_time[keep], st.alpha_final[keep],
                                                                   st.stopped_by[keep])


def _k(case: dict[str, np.ndarray], i: int) -> float:
    return float(case["c"][i] * case["m1"][i] / case["m2"][i])


def _stop_args(case: dict[str, np.ndarray], i: int) -> tuple[float, ...]:
    return (float(case["E_S"][i]), float(case["alpha0"][i]), float(case["F1"][i]), float(case["F2"][i]), _k(case, i),
            float(case["m2"][i]), float(case["L1"][i]))


def _stop_sensitivities(args: tuple[float, ...], t0=None) -> np.ndarray:
    """For each input j (E_S, alpha0, F1, F2, k, m2, L1): |t_F(x with x_j one ulp up) / t_F(x) - 1|, the relative
    change of the exact t_F (mpmath, 30 digits: :func:`reference.stop_time_mpf`, independent of the kernels) when
    that input moves up by one unit in the last place. ``t0``: t_F(x) as an mpmath number, where known."""
    from ..device.reference import stop_time_mpf

    t0 = stop_time_mpf(*args)[0] if t0 is None else t0
    out = np.empty(len(args))
    for j, x in enumerate(args):
        moved = list(args)
        moved[j] = float(np.nextafter(x, math.inf))
        out[j] = float(abs(stop_time_mpf(*moved)[0] / t0 - 1))
    return out


def _stop_sensitivity(args: tuple[float, ...]) -> float:
    """Most relative change of the exact t_F when one input (E_S, alpha0, F1, F2, k, m2, L1) moves by one ulp."""
    return float(np.max(_stop_sensitivities(args)))


def _identify_sensitivities(args: tuple[float, ...], lam) -> np.ndarray:
    """For each input j (alpha0, alpha_F, t_F, E_S, k, m2, L1): how far the exact (F1, F2) move, relative to the
    unmoved F1*, F2* (the error's scale; the larger of the two), when that input moves up by one ulp [-].

    To first order in lambda = F1/F1* (a one-ulp move): with t(lambda) the stop time on the line of Eq. 13 (mpmath,
    30 digits: :func:`reference.line_time_mpf`) and ``lam`` the exact root of t(lambda) = t_F
    (:func:`reference.identify_lambda_mp`), lambda moves by -(g_j - g) / t'(lambda), g = t(lambda) - t_F at the
    unmoved and g_j at the moved inputs, t' by a difference of 1e-12 in lambda; F1* and F2* (Eq. 11-12) move exactly.
    (Where a one-ulp move shifts lambda by more than about 1e-3, the linear estimate is not the exact change, but
    either says the observation does not determine the friction.)"""
    import mpmath as mp

    from ..device.reference import line_time_mpf

    t_lam, F1s, F2s = line_time_mpf(lam, *args[:2], *args[3:])
    h = mp.mpf("1e-12") * (1 if lam < 0.5 else -1)
    slope = (line_time_mpf(lam + h, *args[:2], *args[3:])[0] - t_lam) / h
    g = t_lam - mp.mpf(args[2])
    out = np.empty(len(args))
    for j, x in enumerate(args):
        moved = list(args)
        moved[j] = float(np.nextafter(x, math.inf))
        t_j, F1j, F2j = (t_lam, F1s, F2s) if j == 2 else line_time_mpf(lam, *moved[:2], *moved[3:])
        if slope == 0:  # t_F the same all along the line, to 30 digits: the inputs do not determine lambda at all
            out[j] = math.inf
            continue
        lam_j = lam - (t_j - mp.mpf(moved[2]) - g) / slope
        out[j] = float(max(abs(lam_j * F1j - lam * F1s) / F1s, abs((1 - lam_j) * F2j - (1 - lam) * F2s) / F2s))
    return out


def _backward_ulps(err: np.ndarray, condition: np.ndarray) -> np.ndarray:
    """The backward error in ulps of the inputs: ``err / condition``, where ``condition`` is the case's 1-ulp
    condition number, the sum over the inputs of the change one ulp of each makes (to first order, the most a move
    of every input by at most one ulp can change the exact answer); NaN where either is unknown."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.isnan(condition), np.nan, np.where(err == 0, 0.0, err / condition))


def _weighted_median(values: np.ndarray, weights: np.ndarray) -> float:
    order = np.argsort(values)
    cum = np.cumsum(weights[order])
    return float(values[order][np.searchsorted(cum, 0.5 * cum[-1])])


def _stats(err: np.ndarray, stratum: np.ndarray, sample: str) -> tuple[float | None, float | None]:
    """(median weighted by the strata's shares, worst) of the finite errors; None where there are none."""
    ok = np.isfinite(err)
    if not ok.any():
        return None, None
    shares = np.array([s for _, s in _strata(sample)])
    counts = np.bincount(stratum[ok], minlength=shares.size)
    w = shares[stratum[ok]] / counts[stratum[ok]]
    return _weighted_median(err[ok], w), float(np.max(err[ok]))


def _stop_accuracy(sample: str, sizes: Sizes, seed: int, log) -> dict[str, Any]:
    from ..device.reference import stop_time_mpf

    case, st = _accuracy_cases(sample, sizes.stop_time, seed, friction_stops=False)
    n = len(case["E_S"])
    ref, ivp, ivp_time = np.empty(n), np.empty(n), np.empty(n)
    ref_mp = []
    for i in range(n):
        args = _stop_args(case, i)
        t0 = time.perf_counter()
        try:
            ivp[i] = _solve_ivp_stop(*args)
        except (ValueError, RuntimeError, ZeroDivisionError, OverflowError):
            ivp[i] = math.nan
        ivp_time[i] = time.perf_counter() - t0
        ref_mp.append(stop_time_mpf(*args)[0])
        ref[i] = float(ref_mp[i])
        if (i + 1) % 20 == 0 or i + 1 == n:
            log(f"  {sample} sample: {i + 1}/{n} stop times against mpmath")
    with np.errstate(invalid="ignore"):
        err_k, err_ivp = np.abs(st.stop_time / ref - 1), np.abs(ivp / ref - 1)
    return _accuracy_summary(sample, case["stratum"], err_k, err_ivp, ivp_time, "solve_ivp",
                             lambda i: _stop_sensitivities(_stop_args(case, i), ref_mp[i]), sizes, log)


def _identify_accuracy(sample: str, sizes: Sizes, seed: int, log) -> dict[str, Any]:
    import warnings

    from ..device.reference import identify_lambda_mp

    case, st = _accuracy_cases(sample, sizes.identify, seed, friction_stops=True)
    n = len(case["E_S"])
    ident = batch.identify(case["alpha0"], st.alpha_final, st.stop_time, case["E_S"], case["c"], case["m1"],
                           case["m2"], case["L1"])
    err_k, err_q, q_time = np.full(n, np.nan), np.full(n, np.nan), np.empty(n)
    lams: list[Any] = [None] * n  # the exact lambda = F1/F1* of each case (mpmath)
    args = [(float(case["alpha0"][i]), float(st.alpha_final[i]), float(st.stop_time[i]), float(case["E_S"][i]),
             _k(case, i), float(case["m2"][i]), float(case["L1"][i])) for i in range(n)]
    for i in range(n):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            t0 = time.perf_counter()
            try:
                qb = _quad_brentq_identify(*args[i])
            except (ValueError, RuntimeError, ZeroDivisionError, OverflowError):
                qb = (math.nan, math.nan)
            q_time[i] = time.perf_counter() - t0
        start = float(ident.F1[i]) if ident.status[i] == 0 else None
        try:
            lam, F1s, F2s = identify_lambda_mp(*args[i], start=start)
        except (ValueError, ZeroDivisionError):  # no root on the line in exact arithmetic either: nothing to compare
            continue
        lams[i] = lam
        if ident.status[i] == 0:
            err_k[i] = max(float(abs(ident.F1[i] / F1s - lam)), float(abs(ident.F2[i] / F2s - (1 - lam))))
        if math.isfinite(qb[0]):
            err_q[i] = max(float(abs(qb[0] / F1s - lam)), float(abs(qb[1] / F2s - (1 - lam))))
        if (i + 1) % 10 == 0 or i + 1 == n:
            log(f"  {sample} sample: {i + 1}/{n} identifications against mpmath")
    out = _accuracy_summary(sample, case["stratum"], err_k, err_q, q_time, "quad_brentq",
                            lambda i: _identify_sensitivities(args[i], lams[i]), sizes, log)
    out["infeasible"] = int(np.sum(ident.status != 0))
    return out


def _accuracy_summary(sample, stratum, err_k, err_b, base_time, base, sensitivities, sizes, log) -> dict[str, Any]:
    """Median and worst of the kernel and the baseline (per stratum on the wide sample), the baseline's rate (per
    case, the strata weighed by their shares), the conditioning and the backward error.

    ``sensitivities(i)``: the one-ulp changes of case i's exact answer, one per input (:func:`_stop_sensitivities`,
    :func:`_identify_sensitivities`). Its sum is the case's *1-ulp condition number* and ``err / condition`` its
    *backward error in ulps* (:func:`_backward_ulps`); computed for every case with ``sizes.case_conditioning``, else
    for the worst case(s) and those above the 1e-10 floor of the target only (the backward error is then not given)."""
    shares = np.array([s for _, s in _strata(sample)])
    counts = np.bincount(stratum, minlength=shares.size)
    w = shares[stratum] / counts[stratum]
    out: dict[str, Any] = {"accuracy_cases": int(err_k.size)}
    out["median_rel_error"], out["max_rel_error"] = _stats(err_k, stratum, sample)
    out[f"{base}_median_rel_error"], out[f"{base}_max_rel_error"] = _stats(err_b, stratum, sample)
    out[f"{base}_cases_per_s"] = float(w.sum() / np.sum(w * base_time))
    out[f"{base}_failures"] = int(np.sum(~np.isfinite(err_b)))
    finite = np.isfinite(err_k)
    worst = int(np.argmax(np.where(finite, err_k, -1.0)))
    strata_worst = [int(sel[np.argmax(err_k[sel])]) for j in range(shares.size)
                    if (sel := np.flatnonzero((stratum == j) & finite)).size]
    if sizes.case_conditioning:
        need = np.flatnonzero(finite)
    else:
        need = np.flatnonzero(finite & (err_k > _ACCURACY_WORST))
        extra = strata_worst if sample == "wide" and sizes.strata_conditioning else []
        need = np.union1d(need, [worst, *extra] if finite.any() else []).astype(int)
    sens_max, condition = np.full(err_k.size, np.nan), np.full(err_k.size, np.nan)
    for count, i in enumerate(need):
        s = np.asarray(sensitivities(int(i)), dtype=float)
        sens_max[i], condition[i] = np.max(s), np.sum(s)
        if (count + 1) % 20 == 0 or count + 1 == need.size:
            log(f"  {sample} sample: 1-ulp condition numbers by mpmath, {count + 1}/{need.size}")
    backward = _backward_ulps(err_k, condition)

    def known(x):
        return float(x) if np.isfinite(x) else None

    out["worst_case_sensitivity_1ulp"] = known(sens_max[worst])
    out["worst_case_condition_1ulp"] = known(condition[worst])
    if sizes.case_conditioning:
        out["backward_median_ulps"], out["backward_max_ulps"] = _stats(backward, stratum, sample)
    else:
        out["backward_median_ulps"] = out["backward_max_ulps"] = None
    # the target's measure: error over what the target allows the case, max(1e-10, 4 x its condition number)
    allowed = np.maximum(_ACCURACY_WORST, _CONDITIONED * np.nan_to_num(condition, nan=0.0, posinf=np.inf))
    out["max_error_over_allowed"] = float(np.max(err_k[finite] / allowed[finite])) if finite.any() else None
    if sample == "wide":
        rows = []
        for j, (name, _) in enumerate(_strata(sample)):
            sel = np.flatnonzero((stratum == j) & finite)
            row: dict[str, Any] = {"stratum": name, "cases": int(sel.size), "median_rel_error": None,
                                   "max_rel_error": None, f"{base}_max_rel_error": None, "sensitivity_1ulp": None,
                                   "backward_median_ulps": None, "backward_max_ulps": None}
            if sel.size:
                bad = sel[int(np.argmax(err_k[sel]))]
                row.update(median_rel_error=float(np.median(err_k[sel])), max_rel_error=float(err_k[bad]),
                           sensitivity_1ulp=known(sens_max[bad]))
                fb = err_b[sel][np.isfinite(err_b[sel])]
                row[f"{base}_max_rel_error"] = float(np.max(fb)) if fb.size else None
                bw = backward[sel][np.isfinite(backward[sel])]
                if sizes.case_conditioning and bw.size:
                    row.update(backward_median_ulps=float(np.median(bw)), backward_max_ulps=float(np.max(bw)))
            rows.append(row)
        out["strata"] = rows
        out["worst_stratum"] = WIDE_STRATA[int(stratum[worst])][0]
    return out


# -- the run ----------------------------------------------------------------------------------------------------

def _sample(sample: str, n: int, seed: int) -> dict[str, np.ndarray]:
    return random_releases(n, seed=seed) if sample == "bench" else wide_releases(n, seed=seed)


def _status(value: float | None, bound: float, above: bool) -> str:
    if value is None or not math.isfinite(value):
        return "not measured"
    return "met" if (value >= bound if above else value <= bound) else "not met"


def _accuracy_status(median: float | None, over: float | None) -> str:
    """The accuracy target: median error at most 1e-12 and every case's error at most max(1e-10, 4 x its 1-ulp
    condition number), i.e. ``over`` (the most of error / that allowance over the cases) at most 1."""
    if median is None or over is None:
        return "not measured"
    return "met" if median <= _ACCURACY_MEDIAN and over <= 1.0 else "not met"


def _g(x: float) -> str:
    """Two significant digits, exponents written one way (3.3e-6, 1e10)."""
    return f"{x:.2g}".replace("e-0", "e-").replace("e+0", "e").replace("e+", "e")


def _accuracy_note(g: dict[str, Any]) -> str:
    """What the accuracy line says after its target: the worst error, where, its conditioning, the backward error."""
    worst = g["max_rel_error"]
    if worst is None:
        return ""
    where = f" in '{g['worst_stratum']}'" if "worst_stratum" in g else ""
    cond = g["worst_case_condition_1ulp"]
    parts = [f"worst {_g(worst)}{where}"]
    if cond is not None:
        parts.append(f"one ulp of every input moves the exact answer by up to {_g(cond)} there")
    if g["backward_max_ulps"] is not None:
        parts.append(f"backward error median {_g(g['backward_median_ulps'])}, worst {_g(g['backward_max_ulps'])} "
                     "input ulps")
    parts.append(f"the error over what the target allows the case: at most {_g(g['max_error_over_allowed'])}")
    return " (" + "; ".join(parts) + ")"


def _targets(out: dict[str, Any], cores: int) -> list[dict[str, Any]]:
    """One line per target of the benchmark: what, the value measured, and met / not met / not measured."""
    rows = []
    for key, text, sample, what, bound in TARGETS:
        group, name = what.split(".")
        value = out[sample][group][name]
        rows.append({"target": key, "text": text, "value": value, "status": _status(value, bound, True)})
    for sample in ("bench", "wide"):
        for group, label in (("stop_time", "stop time t_F"), ("identify", "identification F1, F2")):
            g = out[sample][group]
            med, worst, over = g["median_rel_error"], g["max_rel_error"], g["max_error_over_allowed"]
            status = _accuracy_status(med, over)
            rows.append({"target": f"{group}_accuracy_{sample}", "value": [med, worst, over], "status": status,
                         "text": f"{label} vs mpmath, {sample} sample: median <= 1e-12, every case <= max(1e-10, "
                                 f"4 x its 1-ulp condition number){_accuracy_note(g)}"})
    for sample in ("bench", "wide"):
        ratio = min(out[sample]["stop_time"]["all_cores_ratio"], out[sample]["identify"]["all_cores_ratio"])
        same = out[sample]["stop_time"]["all_cores_identical"] and out[sample]["identify"]["all_cores_identical"]
        status = "not measured" if cores < 2 else ("met" if ratio >= _CORES and same else "not met")
        rows.append({"target": f"two_cores_{sample}", "value": ratio, "status": status,
                     "text": f"two cores >= 1.8x one core, {sample} sample, the same bytes (measured on {cores} "
                             f"thread(s): {ratio:.2f}x, {'identical' if same else 'DIFFERENT'})"})
    return rows


def run_bench(quick: bool = False, seed: int = 0, log: Callable[[str], Any] = print, *, threads: int | None = None,
              sizes: Sizes | None = None) -> dict[str, Any]:
    """Run the benchmarks; returns the numbers (the ``--json`` keys).

    Parameters
    ----------
    quick : bool
        :data:`QUICK` sizes and no Dask run (else :data:`FULL`).
    seed : int
        Seed of the samples.
    log : callable
        Receives progress lines.
    threads : int, optional
        Threads of the all-cores measurement, 1 to ``numba.config.NUMBA_NUM_THREADS`` (default: all of them;
        the two-core target is "not measured" with fewer than two).
    sizes : Sizes, optional
        Overrides the sizes of ``quick``.
    """
    cores = max_threads() if threads is None else check_threads(threads)
    sizes = sizes or (QUICK if quick else FULL)
    out: dict[str, Any] = {"quick": quick, "seed": seed, "threads": cores, "cpu_count": os.cpu_count()}
    for k, (sample, draw) in enumerate((("bench", "sampling.random_releases"), ("wide", "sampling.wide_releases"))):
        cases = _sample(sample, sizes.cases, seed + 10 * k)
        group = {"sample": draw, **_throughput(cases, cores, sizes.repeat)}
        log(f"{sample} sample ({draw}, {sizes.cases:,} cases), one core: "
            f"{group['stop_time']['cases_per_s']:,.0f} stop times/s, {group['identify']['cases_per_s']:,.0f} "
            f"identifications/s; {cores} threads: {group['stop_time']['all_cores_ratio']:.2f}x and "
            f"{group['identify']['all_cores_ratio']:.2f}x")
        log(f"{sample} sample: scipy one case at a time and 30-digit mpmath references (progress below) ...")
        group["stop_time"].update(_stop_accuracy(sample, sizes, seed + 10 * k + 1, log))
        group["identify"].update(_identify_accuracy(sample, sizes, seed + 10 * k + 2, log))
        for name, base in (("stop_time", "solve_ivp"), ("identify", "quad_brentq")):
            g = group[name]
            g[f"speedup_vs_{base}"] = g["cases_per_s"] / g[f"{base}_cases_per_s"]
        out[sample] = group
    out["targets"] = _targets(out, cores)
    out["gpu"] = _gpu_section(sizes, seed, log)
    if not quick:
        out["uq_dask"] = _uq_dask_1e8(log)
    return out


#: Cases of each sample on the GPU, per case of the CPU's measurement (a GPU needs millions to be busy).
GPU_SCALE = 10


def _gpu_section(sizes: Sizes, seed: int, log) -> dict[str, Any] | None:
    """The GPU backend's throughput and agreement with the CPU kernels on both samples; None without a GPU."""
    from ..batch import _gpu

    if not _gpu.gpu_available():
        log("no GPU found (CuPy with a CUDA device: pip install 'quickrelease[gpu]'): the gpu backend not measured")
        return None
    cupy = _gpu.array_module()

    def synced(func):
        def run():
            res = func()
            _gpu.synchronize(cupy)
            return res
        return run

    name, version = _gpu.device_name()
    out: dict[str, Any] = {"device": name, "cupy": version}
    for k, sample in enumerate(("bench", "wide")):
        n = GPU_SCALE * sizes.cases
        cases = _sample(sample, n, seed + 10 * k)
        args = [cases[key] for key in ("E_S", "alpha0", "F1", "F2")] + [cases["c"] * cases["m1"] / cases["m2"],
                                                                         cases["m2"], cases["L1"]]
        dev = [cupy.asarray(a) for a in args]
        chunk = _gpu.device_chunk(cupy)  # as batch.*(backend="gpu")
        st_dev, _, res = _timed(synced(lambda dev=dev, chunk=chunk: _gpu.stop_arrays(cupy, *dev, chunk=chunk)), n,
                                sizes.repeat)
        st_e2e, _, st = _timed(lambda c=cases: batch.stop_time(**c, backend="gpu"), n, sizes.repeat)
        cpu = batch.stop_time(**cases)
        obs = _observations(cases, cpu)
        m = len(obs["E_S"])
        obs_dev = [cupy.asarray(a) for a in (obs["alpha0"], obs["alpha_final"], obs["stop_time"], obs["E_S"],
                                             obs["c"] * obs["m1"] / obs["m2"], obs["m2"], obs["L1"])]
        id_dev, _, _ = _timed(synced(lambda d=obs_dev, chunk=chunk: _gpu.identify_arrays(cupy, *d, chunk=chunk)), m,
                              sizes.repeat)
        id_e2e, _, idg = _timed(lambda o=obs: batch.identify(**o, backend="gpu"), m, sizes.repeat)
        idc = batch.identify(**obs)
        fin = np.isfinite(cpu.stop_time)
        ok = idc.status == 0
        floor = 8.0 * np.finfo(float).eps * obs["stop_time"][ok] / (idc.stop_time_max[ok] - idc.stop_time_min[ok])
        with np.errstate(invalid="ignore", divide="ignore"):
            agree = {
                "stop_time_max_rel_diff": float(np.max(np.abs(st.stop_time[fin] / cpu.stop_time[fin] - 1.0))),
                "alpha_final_max_rel_diff": float(np.max(np.abs(st.alpha_final / cpu.alpha_final - 1.0))),
                "stopped_by_identical": bool(np.array_equal(st.stopped_by, cpu.stopped_by)),
                "identify_ends_max_rel_diff": float(max(np.max(np.abs(getattr(idg, e)[ok] / getattr(idc, e)[ok] - 1))
                                                        for e in ("stop_time_min", "stop_time_max", "F1_max"))),
                "identify_F1_max_diff_over_tolerance": float(np.max(np.abs(idg.F1[ok] - idc.F1[ok]) / idc.F1_max[ok]
                                                                    / (1e-13 + floor))) if ok.any() else None,
                "identify_status_identical": bool(np.array_equal(idg.status, idc.status)),
            }
        out[sample] = {"cases": n, "stop_time_cases_per_s": st_dev, "stop_time_end_to_end_cases_per_s": st_e2e,
                       "identify_cases": m, "identify_cases_per_s": id_dev, "identify_end_to_end_cases_per_s": id_e2e,
                       **agree}
        del res, dev, obs_dev
        log(f"{sample} sample on the GPU ({name}, {n:,} cases): {st_dev:,.0f} stop times/s and {id_dev:,.0f} "
            f"identifications/s on the device ({st_e2e:,.0f} and {id_e2e:,.0f} from host arrays); max relative "
            f"difference from the CPU kernels: t_F {agree['stop_time_max_rel_diff']:.1e}")
    return out


def _uq_dask_1e8(log) -> dict[str, Any]:
    """uq with 1e8 samples on two local Dask workers: wall time and peak memory of the process tree."""
    import tempfile
    import threading
    from importlib import resources

    try:
        import psutil  # comes with dask.distributed
    except ImportError:
        return {"skipped": "dask not installed (pip install 'quickrelease[dask]')"}
    from ..io.case import load_case
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
    return {"samples": 100_000_000, "workers": 2, "wall_s": wall, "peak_memory_GiB": peak[0] / 2**30,
            "F1_p50_N": result.percentiles["F1"]["p50"]}
