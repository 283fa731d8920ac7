"""Uncertainty of the identified friction: Monte Carlo over the observation scatter, and local
sensitivities from the implicit function theorem.

The inputs of a case file may carry a scatter (``alpha_final = {value = "0.7378 rad", std = "0.01 rad"}``,
or ``{low, high}`` for a uniform one): the angle at release, the final angle, the stop time, and the push
force (or the stored energy). Each sample is identified with the batch kernel (:func:`batch.identify`).

Samples are drawn chunk by chunk, chunk ``j`` from ``SeedSequence([seed, j])``, so a result depends on
the seed and the chunk size only, not on the backend, the number of workers or the order in which chunks
finish. Each chunk is reduced to aggregates (status counts, 65,536-bin histograms of F1 and F2 on edges
fixed before the run, a 128 x 128 joint histogram, moments combined with Chan's formulas); percentiles
come from the histograms (resolution: one bin) and the aggregates are combined in chunk order, so
memory stays bounded by the chunk size and a resumed run gives exactly the result of an uninterrupted one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import batch
from .._results import Summarised
from .._threads import check_threads, refuse_with_dask, using_threads
from .._validate import check_seed, check_size, check_workers
from ..device.statics import strain_energy_coefficient
from ..errors import ParameterError, QuickReleaseError
from ..io.case import Case
from ..report._style import STYLE, styled

__all__ = ["UQResult", "run_uq", "sensitivities", "uq_chunk", "PERCENTILES", "N_BINS"]

PERCENTILES = (2.5, 50.0, 97.5)
N_BINS = 65536
#: Memory of one finished chunk's aggregates (two int64 histograms of N_BINS bins, and the moments) [bytes].
_CHUNK_BYTES = 2 * 8 * N_BINS + 4096
N_BINS_2D = 128
DEFAULT_CHUNK = 1_000_000
_UNITS = {"force": "N", "energy": "J", "alpha0": "rad", "alpha_final": "rad", "stop_time": "s"}


def _check(case: Case) -> None:
    if not case.has_observations:
        raise QuickReleaseError(f"{case.source}: uq needs [observations] alpha_final and stop_time")
    if case.energy_given and "force" in case.uncertainty:
        raise QuickReleaseError(f"{case.source}: [test] force has a scatter but energy is given, and a given E_S "
                                "drives the release: give the scatter to energy, or drop energy (E_S from Eq. 2)")
    if not any(name in _UNITS for name in case.uncertainty):
        raise QuickReleaseError(f"{case.source}: no uncertainty given: write an input as a table, e.g. "
                                "alpha_final = {value = \"0.7378 rad\", std = \"0.01 rad\"}")


def _inputs(case: Case, rng: np.random.Generator | None, n: int) -> dict[str, np.ndarray]:
    """The (sampled, or nominal when rng is None) inputs of the identification, SI."""
    def draw(name: str, nominal: float) -> np.ndarray:
        dist = case.uncertainty.get(name)
        if dist is None or rng is None:
            return np.full(n, nominal)
        return dist.sample(rng, n)

    # a fixed order of draws: the samples depend only on the seed and the chunk
    alpha0 = draw("alpha0", case.alpha0)
    alpha_final = draw("alpha_final", case.alpha_final)
    stop_time = draw("stop_time", case.stop_time)
    if case.energy_given or case.push_force is None:
        E_S = draw("energy", case.stored_energy)
    else:
        P = draw("force", case.push_force)
        E_S = P * P * strain_energy_coefficient(np.clip(alpha0, 1e-9, 0.5 * np.pi - 1e-9), case.device)
    return {"alpha0": alpha0, "alpha_final": alpha_final, "stop_time": stop_time, "E_S": E_S}


def _identify(case: Case, x: dict[str, np.ndarray], backend: str = "numpy") -> batch.BatchIdentification:
    d = case.device
    return batch.identify(x["alpha0"], x["alpha_final"], x["stop_time"], x["E_S"], case.mass_factor, d.m1, d.m2,
                          d.L1, backend=backend)


def _edges(case: Case, seed: int) -> dict[str, np.ndarray]:
    """Histogram edges fixed before the run, from F1* and F2* of a deterministic pilot sample."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, 2**31 - 1]))
    x = _inputs(case, rng, 100_000)
    ident = _identify(case, x)
    ok = np.isfinite(ident.F1_max) & np.isfinite(ident.F2_max) & (ident.F1_max > 0)
    top1 = 1.25 * float(np.max(ident.F1_max[ok])) if np.any(ok) else 1.0
    top2 = 1.25 * float(np.max(ident.F2_max[ok])) if np.any(ok) else 1.0
    return {"F1": np.linspace(0.0, top1, N_BINS + 1), "F2": np.linspace(0.0, top2, N_BINS + 1)}


def uq_chunk(case: Case, seed: int, index: int, size: int, edges: dict[str, np.ndarray],
             backend: str = "numpy") -> dict[str, Any]:
    """Draw chunk ``index`` (``size`` samples), identify every sample (on ``backend``: numpy or gpu), reduce to
    aggregates."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, index]))
    ident = _identify(case, _inputs(case, rng, size), backend)
    ok = ident.status == 0
    F1, F2 = ident.F1[ok], ident.F2[ok]
    h1, _ = np.histogram(F1, edges["F1"])
    h2, _ = np.histogram(F2, edges["F2"])
    h12, _, _ = np.histogram2d(F1, F2, [edges["F1"][:: N_BINS // N_BINS_2D], edges["F2"][:: N_BINS // N_BINS_2D]])
    n_ok = int(ok.sum())
    m1 = float(F1.mean()) if n_ok else 0.0
    m2 = float(F2.mean()) if n_ok else 0.0
    d1, d2 = F1 - m1, F2 - m2
    return {
        "index": index, "n": size, "n_ok": n_ok,
        "status": np.bincount(ident.status.astype(np.int64), minlength=len(batch.IDENTIFY_STATUS)),
        "hist_F1": h1.astype(np.int64), "hist_F2": h2.astype(np.int64), "hist_2d": h12.astype(np.int64),
        "over_F1": int(np.sum(F1 > edges["F1"][-1])), "over_F2": int(np.sum(F2 > edges["F2"][-1])),
        "mean": np.array([m1, m2]),
        # numpy pairwise sums, not BLAS dot products: the same bits in every process, threaded or not
        "comoment": np.array([float(np.sum(d1 * d1)), float(np.sum(d2 * d2)), float(np.sum(d1 * d2))]),
    }


def _combine(parts: list[dict[str, Any]]) -> dict[str, Any]:
    """Combine chunk aggregates in chunk order (Chan et al. for the moments)."""
    total: dict[str, Any] = {}
    n = 0
    mean = np.zeros(2)
    com = np.zeros(3)
    for p in sorted(parts, key=lambda p: p["index"]):
        for key in ("n", "status", "hist_F1", "hist_F2", "hist_2d", "over_F1", "over_F2"):
            total[key] = total[key] + p[key] if key in total else p[key]
        nb = p["n_ok"]
        if nb:
            delta = p["mean"] - mean
            new_n = n + nb
            com = com + p["comoment"] + np.array([delta[0] ** 2, delta[1] ** 2, delta[0] * delta[1]]) * n * nb / new_n
            mean = mean + delta * nb / new_n
            n = new_n
    total["n_ok"] = n
    total["mean"] = mean
    total["comoment"] = com
    return total


def _percentiles(hist: np.ndarray, edges: np.ndarray, qs=PERCENTILES) -> list[float]:
    cum = np.cumsum(hist)
    total = cum[-1]
    out = []
    for q in qs:
        target = q / 100.0 * total
        i = int(np.searchsorted(cum, target))
        i = min(i, hist.size - 1)
        before = cum[i - 1] if i else 0
        frac = (target - before) / hist[i] if hist[i] else 0.0
        out.append(float(edges[i] + frac * (edges[i + 1] - edges[i])))
    return out


@dataclass(frozen=True, repr=False)
class UQResult(Summarised):
    """Monte Carlo distribution of the identified friction, with local sensitivities."""

    samples: int
    seed: int
    chunk: int
    inputs: dict[str, str]
    """Each uncertain input and its distribution, in words."""
    nominal: dict[str, float]
    """F1, F2 identified at the nominal inputs [N]."""
    percentiles: dict[str, dict[str, float]]
    """F1 and F2 at the 2.5, 50 and 97.5 percentiles [N]."""
    mean: dict[str, float]
    std: dict[str, float]
    correlation: float
    """Pearson correlation of F1 and F2 over the feasible samples."""
    infeasible_share: float
    """Share of samples the line of Eq. 13 cannot explain."""
    status_counts: dict[str, int]
    resolution: dict[str, float]
    """Histogram bin width, the resolution of the percentiles [N]."""
    overflow: dict[str, int]
    sensitivities: dict[str, dict[str, float]]
    """dF/d(input) at the nominal point, implicit function theorem, analytic partials [N per SI unit of input]."""
    sensitivities_fd: dict[str, dict[str, float]]
    """The same by finite differences of the whole identification (a check)."""
    histograms: dict[str, np.ndarray] = field(repr=False, default_factory=dict)

    def summary(self) -> dict[str, Any]:
        """JSON-ready summary (no histograms)."""
        return {
            "samples": self.samples, "seed": self.seed, "chunk": self.chunk, "inputs": self.inputs,
            "nominal_N": self.nominal, "percentiles_N": self.percentiles, "mean_N": self.mean, "std_N": self.std,
            "correlation_F1_F2": self.correlation, "infeasible_share": self.infeasible_share,
            "status_counts": self.status_counts, "resolution_N": self.resolution, "overflow": self.overflow,
            "sensitivities": self.sensitivities, "sensitivities_fd": self.sensitivities_fd,
        }


def _line_time_partials(alpha0: float, alpha_final: float, F1: float, F2: float, k: float, m2: float,
                        L1: float) -> dict[str, float]:
    """Partial derivatives of the stop time of a release that stops at alpha_F (Eq. 10) [s per SI unit].

    With ``alpha = alpha_F - delta w^2`` (``delta = alpha_F - alpha0``) and
    ``E_S - W_F(alpha) = W_F(alpha_F) - W_F(alpha) = 2 sin(delta w^2 / 2) (A cos m + B sin m)``
    (``A = 2 F1 L1``, ``B = 4 F2 L1``, ``m = alpha_F - delta w^2 / 2``; Eq. 7), the stop time is

        t = int_0^1 g dw,   g = 2 delta w sqrt(M(alpha)) / sqrt(2 sin(delta w^2 / 2) (A cos m + B sin m)),

    ``M = m2 L1^2 (k + sin^2 alpha)`` (Eq. 5), on a fixed domain with a smooth integrand. E_S is implied
    (``E_S = W_F(alpha_F)``, Eq. 8), so t is a function of (alpha0, alpha_F, F1, F2), and its partials are the
    integrals of ``g d(ln g)/dp``, differentiated by hand below and integrated by Gauss-Legendre (nodes doubled
    until two rules agree to 1e-14). Returns ``t`` and ``t_alpha0``, ``t_alpha_final``, ``t_F1``, ``t_F2``.
    """
    delta = alpha_final - alpha0
    A, B = 2.0 * F1 * L1, 4.0 * F2 * L1
    previous = None
    for n in (48, 96, 192, 384, 768):
        x, wt = np.polynomial.legendre.leggauss(n)
        w, wt = 0.5 * (x + 1.0), 0.5 * wt
        w2 = w * w
        alpha = alpha_final - delta * w2
        m = alpha_final - 0.5 * delta * w2
        half = 0.5 * delta * w2
        S = np.sin(half)
        D = A * np.cos(m) + B * np.sin(m)
        Dm = -A * np.sin(m) + B * np.cos(m)
        sa, ca = np.sin(alpha), np.cos(alpha)
        kk = k + sa * sa
        g = 2.0 * delta * w * np.sqrt(m2 * L1 * L1 * kk) / np.sqrt(2.0 * S * D)
        dM = 2.0 * sa * ca / kk                      # d ln M / d alpha
        dS = 0.5 * w2 * np.cos(half) / S             # d ln S / d delta
        # d ln g / dp for p = alpha_F (delta' = 1, alpha' = 1 - w^2, m' = 1 - w^2/2) and p = alpha0
        # (delta' = -1, alpha' = w^2, m' = w^2/2); F1 and F2 enter through D only
        l_aF = 1.0 / delta + 0.5 * dM * (1.0 - w2) - 0.5 * dS - 0.5 * Dm * (1.0 - 0.5 * w2) / D
        l_a0 = -1.0 / delta + 0.5 * dM * w2 + 0.5 * dS - 0.5 * Dm * 0.5 * w2 / D
        l_F1 = -0.5 * 2.0 * L1 * np.cos(m) / D
        l_F2 = -0.5 * 4.0 * L1 * np.sin(m) / D
        out = np.array([wt @ g, wt @ (g * l_a0), wt @ (g * l_aF), wt @ (g * l_F1), wt @ (g * l_F2)])
        if previous is not None and np.all(np.abs(out - previous) <= 1e-14 * np.abs(out) + 1e-300):
            break
        previous = out
    return dict(zip(("t", "t_alpha0", "t_alpha_final", "t_F1", "t_F2"), (float(v) for v in out), strict=True))


def sensitivities(case: Case, h: float = 1e-6) -> tuple[dict[str, dict[str, float]], dict[str, dict[str, float]]]:
    """dF1/dx and dF2/dx at the nominal inputs: analytic (implicit function theorem), and by finite differences.

    The identified (F1, F2) solve two equations: the stop at alpha_F (Eq. 8, ``W_F(alpha_F) - E_S = 0``, which
    is the line of Eq. 13) and the stop time (Eq. 10, ``t(alpha0, alpha_F, F1, F2) - t_F = 0``). By the
    implicit function theorem ``d(F1, F2)/dx = -J^-1 dG/dx`` with J the 2 x 2 Jacobian of the two equations in
    (F1, F2). Every partial is analytic: those of Eq. 7-8 in closed form, those of the stop time by
    differentiating its smooth integral under the integral sign (:func:`_line_time_partials`); with a push
    force, ``E_S = P^2 e(alpha0)`` (Eq. 2) adds ``dE_S/dP = 2 P e`` and ``dE_S/dalpha0 = P^2 e'``. The
    second result re-identifies at perturbed inputs (central differences of relative step ``h``), an
    independent check of the whole chain. Inputs x: alpha0, alpha_final, stop_time and the push force (or
    the stored energy).
    """
    from ..device.statics import strain_energy_coefficient_derivative

    d = case.device
    k = case.mass_factor * d.m1 / d.m2
    base = _inputs(case, None, 1)
    ident = _identify(case, base)
    if ident.status[0] != 0:
        raise QuickReleaseError(f"{case.source}: the nominal observations are infeasible: "
                                f"{batch.IDENTIFY_STATUS[int(ident.status[0])]}")
    force_driven = not (case.energy_given or case.push_force is None)
    names = ["alpha0", "alpha_final", "stop_time", "force" if force_driven else "energy"]
    nominal = {"alpha0": case.alpha0, "alpha_final": case.alpha_final, "stop_time": case.stop_time,
               "force": case.push_force, "energy": case.stored_energy}

    a0, aF, L1 = case.alpha0, case.alpha_final, d.L1
    F1, F2 = float(ident.F1[0]), float(ident.F2[0])
    A, B = 2.0 * F1 * L1, 4.0 * F2 * L1
    tp = _line_time_partials(a0, aF, F1, F2, k, d.m2, L1)
    # G1 = A (sin aF - sin a0) + B (cos a0 - cos aF) - E_S (Eq. 7-8); G2 = t(a0, aF, F1, F2) - t_F (Eq. 10)
    J = np.array([[2.0 * L1 * (math.sin(aF) - math.sin(a0)), 4.0 * L1 * (math.cos(a0) - math.cos(aF))],
                  [tp["t_F1"], tp["t_F2"]]])
    G_x = {"alpha0": np.array([-(A * math.cos(a0) + B * math.sin(a0)), tp["t_alpha0"]]),
           "alpha_final": np.array([A * math.cos(aF) + B * math.sin(aF), tp["t_alpha_final"]]),
           "stop_time": np.array([0.0, -1.0]),
           "energy": np.array([-1.0, 0.0])}
    dF = {name: -np.linalg.solve(J, g) for name, g in G_x.items()}
    if force_driven:
        P = case.push_force
        e, e_prime = strain_energy_coefficient(a0, d), strain_energy_coefficient_derivative(a0, d)
        dF["alpha0"] = dF["alpha0"] + dF["energy"] * float(P * P * e_prime)
        dF["force"] = dF["energy"] * float(2.0 * P * e)
    ift: dict[str, dict[str, float]] = {"F1": {}, "F2": {}}
    fd: dict[str, dict[str, float]] = {"F1": {}, "F2": {}}
    for name in names:
        ift["F1"][name], ift["F2"][name] = float(dF[name][0]), float(dF[name][1])
        step = h * max(abs(nominal[name]), 1e-3)
        up, dn = dict(nominal), dict(nominal)
        up[name] += step
        dn[name] -= step
        iu = _identify(case.replace(**_as_case(name, up[name], case)), _inputs(case.replace(
            **_as_case(name, up[name], case)), None, 1))
        idn = _identify(case.replace(**_as_case(name, dn[name], case)), _inputs(case.replace(
            **_as_case(name, dn[name], case)), None, 1))
        fd["F1"][name] = float((iu.F1[0] - idn.F1[0]) / (2 * step))
        fd["F2"][name] = float((iu.F2[0] - idn.F2[0]) / (2 * step))
    return ift, fd


def _as_case(name: str, value: float, case: Case) -> dict[str, Any]:
    if name == "force":
        return {"push_force": value}
    if name == "energy":
        return {"stored_energy": value}
    return {name: value}


def run_uq(case: Case, samples: int, *, seed: int = 0, chunk: int = DEFAULT_CHUNK, backend: str = "numpy",
           scheduler: str | None = None, workers: int = 2, out: str | Path | None = None, resume: bool = False,
           overwrite: bool = False, figures: bool = True, progress: bool = False,
           log: Any = None, threads: int | None = None) -> UQResult:
    """Monte Carlo over the case's input scatter: the distribution of the identified F1 and F2.

    Parameters
    ----------
    case : Case
        With observations and at least one uncertain input.
    samples : int
        Number of samples (any size: memory is bounded by ``chunk``).
    seed : int
        Seed of the run (chunk j draws from ``SeedSequence([seed, j])``).
    chunk : int
        Samples per chunk.
    backend : {"numpy", "dask", "gpu"}
        ``dask`` runs the chunks on a Dask cluster: ``scheduler`` (an address) or a LocalCluster of
        ``workers`` single-threaded processes; ``gpu`` identifies each chunk on a CUDA GPU (CuPy:
        ``pip install 'quickrelease[gpu]'``; the percentiles agree with the numpy backend's to the histogram's
        resolution, the identified values to 1e-13 of F1*, F2* where the observation is well conditioned).
    out : path, optional
        Folder of the run (a :class:`quickrelease.io.runfolder.RunFolder`): ``manifest.json`` (the
        fingerprint of the case, seed, samples and chunk size), ``chunks/`` (one aggregate file per finished
        chunk, written atomically, each carrying the fingerprint), ``uq.json`` (the result) and
        ``uq_corner.png``/``.svg`` (with ``figures``). The run works in ``.NAME.partial`` beside ``out`` and
        moves it into place when complete; an interrupted run leaves it there, to be resumed.
    resume : bool
        Continue the unfinished run of ``out`` (refused, naming what differs, when its fingerprint is not
        this run's): finished chunks are kept, damaged ones (a truncated file) recomputed.
    overwrite : bool
        Replace a folder holding another run (or discard an unfinished one).
    progress : bool
        Show a progress bar (rich).
    log : callable, optional
        Receives one line per note (a damaged chunk recomputed).
    threads : int, optional
        Threads of the compiled kernels, 1 to ``numba.config.NUMBA_NUM_THREADS`` (numpy backend only; default:
        numba's current count, all cores unless changed; :func:`quickrelease.using_threads`). The result is the
        same for any count. Refused with the Dask backend, whose tasks run on one thread each, and the gpu backend.
    """
    _check(case)
    if not isinstance(samples, int | np.integer) or samples < 1:
        raise ParameterError("samples", samples, "integers >= 1")
    if not isinstance(chunk, int | np.integer) or chunk < 1:
        raise ParameterError("chunk", chunk, "integers >= 1")
    if backend not in ("numpy", "dask", "gpu"):
        raise ParameterError("backend", backend, "'numpy', 'dask' or 'gpu'")
    from .distributed import check_optional

    check_optional(backend=backend)  # before any work and before the output folder
    check_seed("seed", seed)
    check_workers("workers", workers)
    check_threads(threads)
    refuse_with_dask(threads, backend)
    check_size("chunk", chunk, chunk, "samples in a chunk")
    check_size("samples", samples, -(-samples // chunk), f"chunks of {chunk}", bytes_each=_CHUNK_BYTES)
    if resume and out is None:
        raise ParameterError("resume", True, "runs with an output folder (out)")
    with using_threads(threads):
        return _run(case, samples, seed, chunk, backend, scheduler, workers, out, resume, overwrite, figures,
                    progress, log)


def _run(case, samples, seed, chunk, backend, scheduler, workers, out, resume, overwrite, figures, progress,
         log) -> UQResult:
    sizes = [min(chunk, samples - i) for i in range(0, samples, chunk)]
    folder = None
    if out is not None:  # pre-flight: before any work
        from ..io.runfolder import RunFolder, case_inputs

        folder = RunFolder(out, "uq", {"case": case_inputs(case), "samples": int(samples), "seed": int(seed),
                                       "chunk": int(chunk)}, overwrite=overwrite, resume=resume, resumable=True)
    edges = _edges(case, seed)
    if folder is None:
        return _result(case, samples, seed, chunk, _combine(_run_chunks(case, seed, sizes, edges, {}, None, backend,
                                                                        scheduler, workers, progress)), edges)
    from ..io.runfolder import output_error

    notes = list(folder.notes)
    work = folder.open()
    try:
        store = _ChunkStore(work, folder.fingerprint, sizes)
        done = store.load()
        notes += store.notes
        for line in notes:
            if log is not None:
                log(line)
        parts = _run_chunks(case, seed, sizes, edges, done, store, backend, scheduler, workers, progress)
        result = _result(case, samples, seed, chunk, _combine(parts), edges)
        from ..io.export import write_json
        from ..io.runfolder import provenance

        write_json(result.summary(), work / "uq.json", provenance(case))
        if figures:
            from ..report.plots import save_figure

            save_figure(corner_figure(result), work, "uq_corner")
    except OSError as exc:  # a full disk: nothing is left (a resumed run's earlier chunks stay)
        folder.abandon(force=True)
        raise output_error(exc, out) from None
    folder.commit()
    return result


def _run_chunks(case, seed, sizes, edges, done, store, backend, scheduler, workers, progress) -> list[dict[str, Any]]:
    """Compute the chunks not in ``done`` (saving each to ``store`` as it finishes); all parts."""
    todo = [i for i in range(len(sizes)) if i not in done]
    parts = list(done.values())
    bar = _progress(progress, len(sizes), len(done))
    if backend in ("numpy", "gpu"):
        for i in todo:
            part = uq_chunk(case, seed, i, sizes[i], edges, backend)
            if store:
                store.save(part)
            parts.append(part)
            bar.advance()
    else:
        from .distributed import map_chunks

        for part in map_chunks(uq_chunk, [(case, seed, i, sizes[i], edges) for i in todo], scheduler, workers):
            if store:
                store.save(part)
            parts.append(part)
            bar.advance()
    bar.close()
    return parts


def _result(case, samples, seed, chunk, total, edges) -> UQResult:
    n_ok = total["n_ok"]
    mean = total["mean"]
    com = total["comoment"]
    var = com / max(n_ok - 1, 1)
    corr = float(com[2] / math.sqrt(com[0] * com[1])) if com[0] > 0 and com[1] > 0 else float("nan")
    pct = {name: dict(zip([f"p{q:g}" for q in PERCENTILES], _percentiles(total[f"hist_{name}"], edges[name]),
                          strict=True)) for name in ("F1", "F2")}
    counts = {batch.IDENTIFY_STATUS[i]: int(c) for i, c in enumerate(total["status"]) if c}
    nominal_ident = _identify(case, _inputs(case, None, 1))
    ift, fd = sensitivities(case)
    return UQResult(
        samples=int(samples), seed=int(seed), chunk=int(chunk),
        inputs={k: v.describe(_UNITS[k]) for k, v in case.uncertainty.items() if k in _UNITS},
        nominal={"F1": float(nominal_ident.F1[0]), "F2": float(nominal_ident.F2[0])},
        percentiles=pct, mean={"F1": float(mean[0]), "F2": float(mean[1])},
        std={"F1": float(math.sqrt(var[0])), "F2": float(math.sqrt(var[1]))},
        correlation=corr, infeasible_share=float(1.0 - n_ok / total["n"]), status_counts=counts,
        resolution={name: float(edges[name][1] - edges[name][0]) for name in ("F1", "F2")},
        overflow={"F1": int(total["over_F1"]), "F2": int(total["over_F2"])},
        sensitivities=ift, sensitivities_fd=fd,
        histograms={"F1": total["hist_F1"], "F2": total["hist_F2"], "2d": total["hist_2d"],
                    "edges_F1": edges["F1"], "edges_F2": edges["F2"]},
    )


class _ChunkStore:
    """Finished chunks of a run, one ``.npz`` per chunk, written atomically, each carrying the run's
    fingerprint; a chunk that cannot be read whole, or belongs to another run, is recomputed."""

    def __init__(self, folder: Path, fingerprint: str, sizes: list[int]) -> None:
        self.chunks = folder / "chunks"
        self.fingerprint = fingerprint
        self.sizes = sizes
        self.notes: list[str] = []
        self.chunks.mkdir(parents=True, exist_ok=True)

    def _read(self, path: Path) -> dict[str, Any]:
        """One chunk file, checked whole; raises ValueError saying what is wrong."""
        import zipfile

        try:
            with np.load(path, allow_pickle=False) as z:
                part = {k: z[k] for k in z.files}
        except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as exc:
            raise ValueError(f"unreadable ({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''})"
                             ) from None
        shapes = {"index": (), "n": (), "n_ok": (), "status": (len(batch.IDENTIFY_STATUS),), "hist_F1": (N_BINS,),
                  "hist_F2": (N_BINS,), "hist_2d": (N_BINS_2D, N_BINS_2D), "over_F1": (), "over_F2": (),
                  "mean": (2,), "comoment": (3,), "fingerprint": ()}
        for key, shape in shapes.items():
            if key not in part or part[key].shape != shape:
                raise ValueError(f"incomplete (entry {key!r} missing or misshapen)")
        if str(part["fingerprint"]) != self.fingerprint:
            raise ValueError("written by a run with other inputs")
        part = {k: (v.item() if v.ndim == 0 else v) for k, v in part.items()}
        index = part["index"]
        expected = f"chunk-{index:06d}.npz" if isinstance(index, int) else None
        if expected != path.name or not 0 <= index < len(self.sizes) or part["n"] != self.sizes[index]:
            raise ValueError(f"holds chunk {index} of size {part['n']}, not the chunk its name says")
        if int(np.sum(part["status"])) != part["n"] or int(part["status"][0]) != part["n_ok"]:
            raise ValueError("inconsistent counts")
        return part

    def load(self) -> dict[int, dict[str, Any]]:
        """The finished chunks by index; damaged files are removed (and noted) so they are recomputed."""
        done = {}
        for path in sorted(self.chunks.glob("chunk-*.npz")):
            try:
                part = self._read(path)
            except ValueError as exc:
                self.notes.append(f"{path}: {exc}: recomputing that chunk")
                path.unlink()
                continue
            done[int(part["index"])] = part
        return done

    def save(self, part: dict[str, Any]) -> None:
        from ..io.export import atomic_path

        with atomic_path(self.chunks / f"chunk-{part['index']:06d}.npz") as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, fingerprint=np.array(self.fingerprint),
                         **{k: np.asarray(v) for k, v in part.items()})


class _NoBar:
    def advance(self) -> None:
        pass

    def close(self) -> None:
        pass


class _Bar:
    def __init__(self, total: int, done: int) -> None:
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

        self.progress = Progress(TextColumn("uq chunks"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn(),
                                 transient=True)
        self.progress.start()
        self.task = self.progress.add_task("uq", total=total, completed=done)

    def advance(self) -> None:
        self.progress.advance(self.task)

    def close(self) -> None:
        self.progress.stop()


def _progress(enabled: bool, total: int, done: int):
    return _Bar(total, done) if enabled else _NoBar()


@styled
def corner_figure(result: UQResult, fig=None, ax=None):
    """Histograms of F1 and F2 and their joint distribution (a corner plot) with the 95% intervals. ``ax``: four
    Axes to draw into (2 x 2, in reading order; the top right one holds the numbers). Returns the figure."""
    from ..report._style import panels

    fig, axes = panels(6.0, 5.8, (2, 2), fig=fig, ax=ax, left=0.12, right=0.97, bottom=0.1, top=0.88, wspace=0.08,
                       hspace=0.12)
    h = result.histograms
    coarse = N_BINS // 512
    for panel, name in ((axes[0, 0], "F1"), (axes[1, 1], "F2")):
        counts = h[name].reshape(-1, coarse).sum(axis=1)
        edges = h[f"edges_{name}"][::coarse]
        centers = 0.5 * (edges[1:] + edges[:-1])
        nz = counts > 0
        lo, hi = np.nonzero(nz)[0][[0, -1]] if np.any(nz) else (0, counts.size - 1)
        panel.fill_between(centers[lo:hi + 1], counts[lo:hi + 1], step="mid", color="#1f4e79", alpha=0.7)
        for key in ("p2.5", "p50", "p97.5"):
            panel.axvline(result.percentiles[name][key], color="#c0504d", lw=0.9, ls="--" if key != "p50" else "-")
        panel.set_yticks([])
        panel.set_xlim(edges[lo], edges[hi + 1])
    axes[0, 0].set_title("$F_1$: median (line), 95% interval (dashed)", fontsize=STYLE["legend.fontsize"])
    axes[1, 1].set_title("$F_2$: median (line), 95% interval (dashed)", fontsize=STYLE["legend.fontsize"])
    axes[0, 0].tick_params(labelbottom=False)  # the same F1 axis as the joint panel below, labelled there
    axes[1, 1].set_xlabel("$F_2$ [N]")
    axes[0, 1].axis("off")
    axes[0, 1].text(0.0, 0.5, "\n".join([
        f"{result.samples:,} samples, seed {result.seed}",
        f"F1: {result.percentiles['F1']['p50']:.1f} N [{result.percentiles['F1']['p2.5']:.1f}, "
        f"{result.percentiles['F1']['p97.5']:.1f}]",
        f"F2: {result.percentiles['F2']['p50']:.1f} N [{result.percentiles['F2']['p2.5']:.1f}, "
        f"{result.percentiles['F2']['p97.5']:.1f}]",
        f"correlation {result.correlation:.3f}",
        f"infeasible {100 * result.infeasible_share:.2f}%"]), fontsize=STYLE["legend.fontsize"], va="center")
    panel = axes[1, 0]
    h2 = h["2d"]
    e1 = h["edges_F1"][:: N_BINS // N_BINS_2D]
    e2 = h["edges_F2"][:: N_BINS // N_BINS_2D]
    panel.pcolormesh(e1, e2, np.ma.masked_equal(h2.T, 0), cmap="Blues", shading="flat", rasterized=True)
    nz1 = np.nonzero(h2.sum(axis=1))[0]
    nz2 = np.nonzero(h2.sum(axis=0))[0]
    if nz1.size and nz2.size:
        panel.set_xlim(e1[nz1[0]], e1[nz1[-1] + 1])
        panel.set_ylim(e2[nz2[0]], e2[nz2[-1] + 1])
        axes[0, 0].set_xlim(e1[nz1[0]], e1[nz1[-1] + 1])
        axes[1, 1].set_xlim(e2[nz2[0]], e2[nz2[-1] + 1])
    panel.set_xlabel("$F_1$ [N]")
    panel.set_ylabel("$F_2$ [N]")
    if ax is None:
        fig.suptitle("Identified friction under observation uncertainty")
    return fig
