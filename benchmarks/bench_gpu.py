"""The GPU path's kernels (:mod:`quickrelease.batch._gpu`) against the compiled CPU kernels, in the same run.

The xp kernels (stop time, identification, release envelope) are written once against an array module. Here they
run with ``xp = numpy`` on one core of this machine (the GPU code on the CPU: for reference only, it is not how they
are meant to run) and, where CuPy sees a CUDA device, with ``xp = cupy`` on the GPU; the baseline is the compiled
CPU kernels (:mod:`quickrelease.batch` stop_time, identify and release, numba) on one core, on the same cases of the
bench and the wide samples. Rates are cases per second of CPU time (``time.process_time``, best of ``--repeat``) on
the CPU, of wall time on the GPU (synchronised); beside them the most relative difference from the compiled kernels
(t_F, the peak head acceleration; lambda over its tolerance, 1e-13 plus ``8 eps t_F / (t_hi - t_lo)``).

Run: PYTHONPATH=src python benchmarks/bench_gpu.py [--n 200000] [--repeat 3]
Prints one JSON object; progress on stderr.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

KEYS = ("E_S", "alpha0", "F1", "F2", "c", "m1", "m2", "L1")


def _best(func, repeat: int, sync=lambda: None) -> tuple[float, float, object]:
    """(best CPU seconds, best wall seconds, last result) of ``repeat`` calls after one warm-up call."""
    result = func()
    sync()
    cpu = wall = float("inf")
    for _ in range(repeat):
        c0, w0 = time.process_time(), time.perf_counter()
        result = func()
        sync()
        cpu, wall = min(cpu, time.process_time() - c0), min(wall, time.perf_counter() - w0)
    return cpu, wall, result


def _inputs(cases):
    k = cases["c"] * cases["m1"] / cases["m2"]
    return [cases["E_S"], cases["alpha0"], cases["F1"], cases["F2"], k, cases["m2"], cases["L1"]]


def measure(n: int, repeat: int, seed: int = 0) -> dict:
    import numba

    from quickrelease import batch
    from quickrelease.batch import _gpu
    from quickrelease.batch.sampling import random_releases, wide_releases

    numba.set_num_threads(1)
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    targets = [("numpy", np, lambda: None)]
    if _gpu.gpu_available():
        cupy = _gpu.array_module()
        targets.append(("cupy", cupy, lambda: _gpu.synchronize(cupy)))
    out = {"cases": n, "gpu": _gpu.device_name()[0] if len(targets) > 1 else None}
    for name, draw in (("bench", random_releases), ("wide", wide_releases)):
        cases = draw(n, seed=seed)
        args = _inputs(cases)
        full = [cases[key] for key in KEYS]
        cpu_s, _, st = _best(lambda full=full: batch.stop_time(*full), repeat)
        fr = st.stopped_by == 0
        obs = [cases["alpha0"][fr], st.alpha_final[fr], st.stop_time[fr], cases["E_S"][fr]]
        obs_k = [a[fr] for a in args[4:]]
        every = obs + [cases[key][fr] for key in KEYS[4:]]
        cpu_i, _, ident = _best(lambda every=every: batch.identify(*every), repeat)
        cpu_r, _, env = _best(lambda full=full: batch.release(*full), repeat)
        row = {"compiled_one_core": {"stop_time_cases_per_s": n / cpu_s, "identify_cases_per_s": fr.sum() / cpu_i,
                                     "release_cases_per_s": n / cpu_r}}
        ok = ident.status == 0
        floor = 8 * np.finfo(float).eps * obs[2][ok] / (ident.stop_time_max[ok] - ident.stop_time_min[ok])
        for target, xp, sync in targets:
            dev = [xp.asarray(a) for a in args]
            dev_obs = [xp.asarray(a) for a in obs + obs_k]
            ch = _gpu.device_chunk(xp)  # the chunk batch.*(backend="gpu") takes on this device
            c_s, w_s, res = _best(lambda xp=xp, ch=ch, dev=dev: _gpu.stop_arrays(xp, *dev, chunk=ch), repeat, sync)
            c_i, w_i, idr = _best(lambda xp=xp, ch=ch, d=dev_obs: _gpu.identify_arrays(xp, *d, chunk=ch), repeat, sync)
            c_r, w_r, rel = _best(lambda xp=xp, ch=ch, dev=dev: _gpu.release_arrays(xp, *dev, chunk=ch), repeat, sync)
            t = _gpu.to_host(res[0])
            peak = _gpu.to_host(rel["peak_u_ddot"])
            lam = _gpu.to_host(idr["lam"])
            fin = np.isfinite(st.stop_time)
            secs_s, secs_i, secs_r = (c_s, c_i, c_r) if target == "numpy" else (w_s, w_i, w_r)
            good = np.isfinite(env.peak_u_ddot)
            row[f"xp_{target}"] = {
                "stop_time_cases_per_s": n / secs_s, "identify_cases_per_s": fr.sum() / secs_i,
                "stop_time_ratio_to_compiled": (n / secs_s) / row["compiled_one_core"]["stop_time_cases_per_s"],
                "identify_ratio_to_compiled": (fr.sum() / secs_i) / row["compiled_one_core"]["identify_cases_per_s"],
                "release_cases_per_s": n / secs_r,
                "release_ratio_to_compiled": (n / secs_r) / row["compiled_one_core"]["release_cases_per_s"],
                "stop_time_max_rel_diff": float(np.max(np.abs(t[fin] / st.stop_time[fin] - 1.0))),
                "peak_u_ddot_max_rel_diff": float(np.max(np.abs(peak[good] / env.peak_u_ddot[good] - 1.0))),
                "lambda_max_diff_over_tolerance": float(np.max(np.abs(lam[ok] - ident.F1[ok] / ident.F1_max[ok])
                                                               / (1e-13 + floor))),
            }
            print(f"{name}: xp={target}: {row[f'xp_{target}']}", file=sys.stderr, flush=True)
        out[name] = row
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=200_000, help="cases of each sample")
    parser.add_argument("--repeat", type=int, default=3, help="timed runs (the best counts)")
    args = parser.parse_args()
    print(json.dumps(measure(args.n, args.repeat), indent=2))


if __name__ == "__main__":
    main()
