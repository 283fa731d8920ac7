"""The batch kernels on the bench sample and the wide sample, against a baseline measured in the same run.

The baseline is the library as of a git revision (``--baseline``, default ``main``): its ``src`` is exported with
``git archive`` into a temporary folder and measured by the same worker in a subprocess, on the same cases (written
once to a temporary ``.npz``). Each worker pins itself to one CPU and sets numba's threads to 1 for the one-core
rates; rates are cases per second of CPU time (``time.process_time``, best of ``--repeat``), wall time beside. With
``--threads N`` (N > 1, at most the CPUs this process may use) the current kernels are measured on N threads too:
the speed-up over one thread (wall time) and whether the results are bit-identical.

* stop time: :func:`quickrelease.batch.stop_time` on every case of each sample;
* identification: :func:`quickrelease.batch.identify` on the friction stops of each sample (alpha_F and t_F from
  the current kernels), the same observations for both;
* accuracy (current kernels): against mpmath (:mod:`quickrelease.device.reference`) on ``--accuracy`` cases of each
  sample (stratified for the wide one): relative error of t_F; error of F1 and F2 relative to F1*, F2*.

Run: PYTHONPATH=src python benchmarks/bench_kernels.py [--n 200000] [--baseline main] [--threads 2] [--accuracy 40]
Prints one JSON object (rates, ratios current / baseline, accuracy); progress on stderr.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
KEYS = ("E_S", "alpha0", "F1", "F2", "c", "m1", "m2", "L1")


def _log(*args):
    print(*args, file=sys.stderr, flush=True)


def _samples(n: int, seed: int) -> dict[str, np.ndarray]:
    """Both samples' cases and the identification observations of their friction stops (flat arrays)."""
    from quickrelease import batch
    from quickrelease.batch.sampling import random_releases, wide_releases

    out = {}
    for name, draw in (("bench", random_releases), ("wide", wide_releases)):
        cases = draw(n, seed=seed)
        for key in KEYS:
            out[f"{name}_{key}"] = np.asarray(cases[key], dtype=float)
        stop = batch.stop_time(*(cases[key] for key in KEYS))
        friction = stop.stopped_by == 0
        out[f"{name}_obs_alpha_final"] = stop.alpha_final[friction]
        out[f"{name}_obs_stop_time"] = stop.stop_time[friction]
        out[f"{name}_obs_index"] = np.nonzero(friction)[0]
    return out


def _best(func, repeat: int) -> tuple[float, float, object]:
    """(best CPU seconds, best wall seconds, last result) of ``repeat`` calls after one warm-up call."""
    result = func()
    cpu = wall = float("inf")
    for _ in range(repeat):
        c0, w0 = time.process_time(), time.perf_counter()
        result = func()
        cpu, wall = min(cpu, time.process_time() - c0), min(wall, time.perf_counter() - w0)
    return cpu, wall, result


def _calls(data, name):
    from quickrelease import batch

    cases = [data[f"{name}_{key}"] for key in KEYS]
    i = data[f"{name}_obs_index"]
    obs = [cases[1][i], data[f"{name}_obs_alpha_final"], data[f"{name}_obs_stop_time"], cases[0][i],
           *(v[i] for v in cases[4:])]
    return (lambda: batch.stop_time(*cases)), (lambda: batch.identify(*obs)), len(cases[0]), len(i)


def worker(path: str, repeat: int, threads: int) -> dict:
    """Rates of the importable quickrelease on the cases of ``path`` (one CPU, one numba thread; and on
    ``threads`` threads when > 1)."""
    import numba

    data = dict(np.load(path))
    cpus = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else []
    # numba's threads start on the first parallel call and keep the affinity they start with: start them now,
    # unpinned, then pin this thread alone for the one-thread rates (sched_setaffinity(0) pins the calling thread)
    _calls(data, "bench")[0]()
    out = {}
    for name in ("bench", "wide"):
        stop, ident, n_stop, n_id = _calls(data, name)
        if cpus:
            os.sched_setaffinity(0, {cpus[0]})
        numba.set_num_threads(1)
        cpu_s, wall_s, res_s = _best(stop, repeat)
        cpu_i, wall_i, res_i = _best(ident, repeat)
        row = {"stop_per_s_cpu": n_stop / cpu_s, "stop_per_s_wall": n_stop / wall_s,
               "identify_per_s_cpu": n_id / cpu_i, "identify_per_s_wall": n_id / wall_i,
               "cases": n_stop, "observations": n_id}
        if threads > 1 and cpus:
            os.sched_setaffinity(0, set(cpus[:threads]))
            numba.set_num_threads(threads)
            _, wall_sn, res_sn = _best(stop, repeat)
            _, wall_in, res_in = _best(ident, repeat)
            row |= {"threads": threads, "stop_speedup": wall_s / wall_sn, "identify_speedup": wall_i / wall_in,
                    "bit_identical": bool(all(np.array_equal(a, b, equal_nan=True) for a, b in (
                        (res_s.stop_time, res_sn.stop_time), (res_s.alpha_final, res_sn.alpha_final),
                        (res_i.F1, res_in.F1), (res_i.F2, res_in.F2), (res_i.iterations, res_in.iterations))))}
        out[name] = row
    if cpus:
        os.sched_setaffinity(0, set(cpus))
    return out


def accuracy(data, n: int) -> dict:
    """Errors of the current kernels against mpmath on n cases of each sample (the wide one stratified)."""
    from quickrelease import batch
    from quickrelease.batch.sampling import wide_releases
    from quickrelease.device.reference import identify_mp, stop_time_mp

    out = {}
    for name in ("bench", "wide"):
        cases = {key: data[f"{name}_{key}"] for key in KEYS}
        if name == "wide":  # n cases spread over the strata (the same draw as the sample: same seed and size)
            stratum = wide_releases(cases["E_S"].size, seed=data["seed"].item(), strata=True)["stratum"]
            pick = np.concatenate([np.nonzero(stratum == s)[0][: -(-n // (stratum.max() + 1))]
                                   for s in range(stratum.max() + 1)])[:n]
        else:
            pick = np.arange(n)
        sub = {key: v[pick] for key, v in cases.items()}
        k = sub["c"] * sub["m1"] / sub["m2"]
        stop = batch.stop_time(*(sub[key] for key in KEYS))
        err_t, err_f = [], []
        for i in range(pick.size):
            if not np.isfinite(stop.stop_time[i]):
                continue
            ref = stop_time_mp(sub["E_S"][i], sub["alpha0"][i], sub["F1"][i], sub["F2"][i], k[i], sub["m2"][i],
                               sub["L1"][i])[0]
            err_t.append(abs(stop.stop_time[i] / ref - 1.0))
            if stop.stopped_by[i] == 0:
                args = (sub["alpha0"][i], stop.alpha_final[i], stop.stop_time[i], sub["E_S"][i])
                got = batch.identify(*args, sub["c"][i], sub["m1"][i], sub["m2"][i], sub["L1"][i])
                if int(got.status) == 0:
                    F1, F2 = identify_mp(*args, k[i], sub["m2"][i], sub["L1"][i])
                    err_f.append(max(abs(float(got.F1) - F1) / float(got.F1_max),
                                     abs(float(got.F2) - F2) / float(got.F2_max)))
        out[name] = {"stop_time_median": float(np.median(err_t)), "stop_time_worst": float(np.max(err_t)),
                     "identify_median": float(np.median(err_f)), "identify_worst": float(np.max(err_f)),
                     "cases": len(err_t), "identifications": len(err_f)}
    return out


def _export(rev: str, into: Path) -> Path:
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "src"], check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive, check=True)
    return into / "src"


def _run_worker(src: Path, path: str, repeat: int, threads: int) -> dict:
    env = {**os.environ, "PYTHONPATH": str(src)}
    cmd = [sys.executable, __file__, "--worker", path, "--repeat", str(repeat), "--threads", str(threads)]
    done = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True)
    return json.loads(done.stdout)


def main(argv=None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, default=200_000, help="cases per sample")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--baseline", default="main", help="git revision measured as the baseline ('' for none)")
    p.add_argument("--threads", type=int, default=2, help="threads of the multi-core measurement (1: none)")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--accuracy", type=int, default=40, help="cases per sample checked against mpmath (0: none)")
    p.add_argument("--worker", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.worker:
        print(json.dumps(worker(args.worker, args.repeat, args.threads)))
        return {}
    import quickrelease

    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "cases.npz")
        data = _samples(args.n, args.seed)
        np.savez(path, seed=np.array(args.seed), **data)
        result = {"n": args.n, "seed": args.seed}
        _log("current kernels ...")
        result["current"] = _run_worker(Path(quickrelease.__file__).parent.parent, path, args.repeat,
                                        args.threads)
        if args.baseline:
            _log(f"baseline {args.baseline} (exported, compiled on first use) ...")
            base = _run_worker(_export(args.baseline, Path(tmp)), path, args.repeat, 1)
            result["baseline"] = {"revision": args.baseline, **base}
            result["ratio"] = {name: {key: result["current"][name][key] / base[name][key]
                                      for key in ("stop_per_s_cpu", "identify_per_s_cpu")} for name in base}
        if args.accuracy:
            _log("accuracy against mpmath ...")
            result["accuracy"] = accuracy(np.load(path), args.accuracy)
    return result


if __name__ == "__main__":
    out = main()
    if out:
        print(json.dumps(out, indent=2))
