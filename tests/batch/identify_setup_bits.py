"""Bit-identity check of the identification's three back-ends across a refactoring (issue 23, item 4).

``python tests/batch/identify_setup_bits.py save FILE.npz`` stores, as arrays, every output of the three back-ends of the
identification on the bench sample, the wide sample and a set of raw observations (infeasible, invalid and
near-boundary ones included):

* ``batch.identify`` (the compiled kernels of ``_fast``, numba),
* ``batch._identify_chunk`` (the numpy reference),
* ``_gpu.identify_arrays`` with ``xp = numpy`` (the GPU back-end's code, run on the CPU),

and the stop-time kernel's outputs that feed them. ``python tests/batch/identify_setup_bits.py compare FILE.npz`` computes
the same with the code checked out now and compares every array with ``np.array_equal`` (NaN equal to NaN, dtype and
shape checked): run ``save`` on the code before a change, ``compare`` after it. Exit code 0 when every array has the
same bits, 1 otherwise (the arrays that differ are named, with the number of elements that do).
"""

from __future__ import annotations

import sys

import numpy as np

from quickrelease import batch
from quickrelease.batch import _gpu
from quickrelease.studies.bench import _observations, _sample

#: Cases of each sample (the bench's default seed, 0) and of the numpy reference (slower: a subset).
N_CASES = 100_000
N_NUMPY = 20_000
KEYS = ("E_S", "alpha0", "F1", "F2", "c", "m1", "m2", "L1")
IDENT = ("F1", "F2", "F1_max", "F2_max", "stop_time_min", "stop_time_max", "status", "iterations")


def _raw_observations(n: int = 20_000, seed: int = 7) -> dict[str, np.ndarray]:
    """Observations drawn without the stop-time kernel: t_F anywhere (statuses 1 and 2), angles near 0, near each
    other and near pi/2, a few invalid entries (statuses 3 to 5), and E_S over six decades."""
    rng = np.random.default_rng(seed)
    a0 = rng.uniform(1e-6, 1.5, n)
    gap = 10.0 ** rng.uniform(-12, 0, n)
    aF = np.minimum(a0 + gap * (0.5 * np.pi - a0), np.nextafter(0.5 * np.pi, 0.0))
    aF[:200] = np.nextafter(0.5 * np.pi, 0.0)
    aF[200:300] = np.nextafter(a0[200:300], 1.0)
    tF = 10.0 ** rng.uniform(-3, 1, n)
    E = 10.0 ** rng.uniform(1, 7, n)
    c = np.where(rng.random(n) < 0.5, 2.0 / 3.0, 1.0)
    m1 = rng.uniform(50.0, 2000.0, n)
    m2 = rng.uniform(50.0, 2000.0, n)
    L1 = rng.uniform(0.3, 3.0, n)
    a0[300:310] = -0.1
    aF[310:320] = a0[310:320] - 0.01
    tF[320:330] = -1.0
    E[330:340] = np.nan
    return dict(alpha0=a0, alpha_final=aF, stop_time=tF, E_S=E, c=c, m1=m1, m2=m2, L1=L1)


def _valid(obs: dict[str, np.ndarray]) -> np.ndarray:
    a0, aF = obs["alpha0"], obs["alpha_final"]
    with np.errstate(invalid="ignore"):
        return ((a0 > 0) & (a0 < 0.5 * np.pi) & (aF > a0) & (aF < 0.5 * np.pi) & (obs["stop_time"] > 0)
                & (obs["E_S"] > 0) & np.isfinite(obs["E_S"]))


def outputs() -> dict[str, np.ndarray]:
    """Every output of the three back-ends on the three sets of observations, by name."""
    out: dict[str, np.ndarray] = {}
    sets = {}
    for sample in ("bench", "wide"):
        cases = _sample(sample, N_CASES, 0)
        st = batch.stop_time(**{key: cases[key] for key in KEYS})
        for name in ("stop_time", "alpha_final", "stopped_by"):
            out[f"{sample}.stop.{name}"] = getattr(st, name)
        sets[sample] = _observations(cases, st)
    sets["raw"] = _raw_observations()
    for name, obs in sets.items():
        ident = batch.identify(**obs)
        for key in IDENT:
            out[f"{name}.fast.{key}"] = getattr(ident, key)
        ok = _valid(obs)
        a0, aF, tF, E, c, m1, m2, L1 = (np.ascontiguousarray(obs[key][ok], dtype=float) for key in (
            "alpha0", "alpha_final", "stop_time", "E_S", "c", "m1", "m2", "L1"))
        k = c * m1 / m2
        gpu = _gpu.identify_arrays(np, a0, aF, tF, E, k, m2, L1)
        for key, v in gpu.items():
            out[f"{name}.gpu_numpy.{key}"] = np.asarray(v)
        m = min(N_NUMPY, a0.size)
        for lo in range(0, m, batch.CHUNK):
            sl = slice(lo, min(m, lo + batch.CHUNK))
            with np.errstate(all="ignore"):
                part = batch._identify_chunk(a0[sl], aF[sl], tF[sl], E[sl], k[sl], m2[sl], L1[sl], 1e-14, 40)
            for key, v in part.items():
                out.setdefault(f"{name}.numpy.{key}", []).append(np.asarray(v))
    return {key: (np.concatenate(v) if isinstance(v, list) else v) for key, v in out.items()}


def compare(before: dict[str, np.ndarray], after: dict[str, np.ndarray]) -> list[str]:
    """The names whose arrays differ (in shape, dtype or any element; NaN equals NaN), each with a count."""
    bad = [f"{key}: missing" for key in sorted(before.keys() ^ after.keys())]
    for key in sorted(before.keys() & after.keys()):
        a, b = before[key], after[key]
        if a.shape != b.shape or a.dtype != b.dtype:
            bad.append(f"{key}: shape/dtype {a.shape} {a.dtype} vs {b.shape} {b.dtype}")
        elif not np.array_equal(a, b, equal_nan=a.dtype.kind == "f"):
            differ = ~((a == b) | (np.isnan(a) & np.isnan(b))) if a.dtype.kind == "f" else a != b
            bad.append(f"{key}: {int(np.sum(differ))} of {a.size} differ")
    return bad


def main(argv: list[str]) -> int:
    if len(argv) != 3 or argv[1] not in ("save", "compare"):
        print("usage: python tests/batch/identify_setup_bits.py save|compare FILE.npz", file=sys.stderr)
        return 2
    now = outputs()
    if argv[1] == "save":
        np.savez(argv[2], **now)
        print(f"{len(now)} arrays, {sum(v.size for v in now.values())} values saved to {argv[2]}")
        return 0
    with np.load(argv[2]) as f:
        before = {key: f[key] for key in f.files}
    bad = compare(before, now)
    for line in bad:
        print(line)
    print(f"{len(before)} arrays, {sum(v.size for v in before.values())} values: "
          f"{'all bit-identical' if not bad else f'{len(bad)} differ'}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
