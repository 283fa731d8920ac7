"""Vectorized kernels over many releases: stop times, release envelopes, identification.

Arrays of cases in, arrays of answers out, no Python loop per case: the closed-form alpha_F (Eq. 8)
and a fixed-node Gauss quadrature of the first integral (Eq. 10) after the substitution of
:mod:`quickrelease.device._kernels`, which leaves only square roots and arithmetic at the nodes and writes
the integrand without cancellation. Inputs broadcast against each other (numpy rules); cases are
processed in chunks that fit the CPU cache.

* :func:`stop_time` - t_F, alpha_F and why the motion ended (the fast kernel).
* :func:`release` - the same plus the stroke u_F, the opening v_F and the peak velocities.
* :func:`identify` - F1, F2 on the line of Eq. 13 from (alpha0, alpha_F, t_F, E_S), by Halley's
  method in lambda = F1/F1* on the same nodes (which do not depend on F1); infeasible cases are
  flagged with a reason code (:data:`IDENTIFY_STATUS`), never dropped.

All SI units. ``c`` is the mass factor (2/3 distributed, 1 lumped); ``m1``, ``m2``, ``L1`` default
to the paper's device.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from ..device import _kernels, dynamics
from ..device._kernels import HALF_PI, gauss_unit, graded_unit
from ..errors import ParameterError
from . import _identify_setup

__all__ = [
    "CHUNK", "BatchStop", "BatchRelease", "BatchIdentification", "IDENTIFY_STATUS", "STOPPED_BY",
    "stop_time", "release", "identify",
]

#: Cases per chunk: keeps the (nodes x cases) work arrays in the CPU cache.
CHUNK = 2048

#: Codes of ``stopped_by`` arrays.
#: 2: the margin E_S - W_F(pi/2) within its rounding of 0 without rail friction: the device creeps towards pi/2
#: and never arrives (stop_time = inf, alpha_final = pi/2: :func:`quickrelease.device.dynamics.creeps_terms`).
STOPPED_BY = {0: "friction", 1: "geometric_limit", 2: "creeps_to_limit"}

#: Codes of :attr:`BatchIdentification.status` and what they mean.
IDENTIFY_STATUS = {
    0: "ok",
    1: "t_F below t_F(F1 = 0): faster than any friction on the line of Eq. 13 allows",
    2: "t_F above t_F(F1 = F1*): slower than any friction on the line of Eq. 13 allows",
    3: "alpha_final not in (alpha0, pi/2)",
    4: "alpha0 not in (0, pi/2)",
    5: "E_S, t_F, c, m1, m2 or L1 not positive and finite",
}


def _paper_defaults(m1, m2, L1):
    if m1 is None or m2 is None or L1 is None:
        from ..device.parameters import preset

        d = preset("paper")
        m1 = d.m1 if m1 is None else m1
        m2 = d.m2 if m2 is None else m2
        L1 = d.L1 if L1 is None else L1
    return m1, m2, L1


def _flat(*arrays) -> tuple[tuple[int, ...], list[np.ndarray]]:
    arrays = [np.asarray(a, dtype=float) for a in arrays]
    shape = np.broadcast_shapes(*(a.shape for a in arrays))
    # the compiled kernels take writeable contiguous arrays: broadcast inputs are copied out, and so are read-only
    # ones (a read-only array is another type to numba: a second compilation of each kernel, seconds, for the same
    # work)
    return shape, [_writeable(np.ascontiguousarray(a).ravel()) if a.shape == shape
                   else np.array(np.broadcast_to(a, shape)).ravel() for a in arrays]


def _writeable(a: np.ndarray) -> np.ndarray:
    """``a`` itself where it is writeable, else a copy."""
    return a if a.flags.writeable else a.copy()


class _Result:
    """Shared conversions of the batch result types."""

    def to_dict(self) -> dict[str, np.ndarray]:
        return {f.name: getattr(self, f.name) for f in fields(self) if getattr(self, f.name) is not None}

    def to_pandas(self):
        import pandas as pd

        return pd.DataFrame({k: np.ravel(v) for k, v in self.to_dict().items()})

    def __len__(self) -> int:
        return int(np.size(getattr(self, fields(self)[0].name)))


@dataclass(frozen=True)
class BatchStop(_Result):
    """Stop time and final angle of many releases (arrays of the broadcast input shape)."""

    stop_time: np.ndarray
    """t_F [s]: to the friction stop, or to the flat rhombus (inf where the device creeps towards it)."""
    alpha_final: np.ndarray
    """alpha_F [rad] (pi/2 at the geometric limit)."""
    stopped_by: np.ndarray
    """0 friction, 1 geometric limit, 2 creeps to the limit (see :data:`STOPPED_BY`)."""

    @property
    def geometric_limit(self) -> np.ndarray:
        return self.stopped_by == 1


@dataclass(frozen=True)
class BatchRelease(_Result):
    """Stop, stroke, opening and peak velocities of many releases."""

    stop_time: np.ndarray
    """t_F [s] (inf where the device creeps towards the flat rhombus, stopped_by 2)."""
    alpha_final: np.ndarray
    """alpha_F [rad]."""
    stopped_by: np.ndarray
    """0 friction, 1 geometric limit, 2 creeps to the limit (t_F = inf; see :data:`STOPPED_BY`)."""
    u_final: np.ndarray
    """Head stroke u_F [m] (Table 4)."""
    v_final: np.ndarray
    """Central hinge opening v_F [m] (Table 4)."""
    alpha_dot0: np.ndarray
    """Initial (and peak) angular velocity [rad/s] (Eq. 6)."""
    peak_u_dot: np.ndarray
    """Peak head velocity [m/s]."""
    peak_v_dot: np.ndarray
    """Peak central hinge velocity [m/s] (at release)."""
    peak_u_ddot: np.ndarray
    """Peak |head acceleration| during the motion [m/s^2] (Table 4, alpha_ddot from Eq. 3/4): the maximum at a
    root of the jerk, accurate to 1e-8 relative or better (about 1e-12 measured; never above the true maximum
    by more than rounding)."""
    peak_v_ddot: np.ndarray
    """Peak |central hinge acceleration| during the motion [m/s^2], to the same accuracy."""
    status: np.ndarray | None = None
    """0 computed; 1 outside the floating-point range (see :data:`RELEASE_STATUS`; every output NaN)."""


#: Status of a case of :func:`release` (``BatchRelease.status``).
RELEASE_STATUS = {
    0: "ok",
    1: "outside the floating-point range: E_S, 2 F1 L1 or 4 F2 L1 is not a finite positive float, or a result "
       "overflows (outputs NaN)",
}

#: Friction whose work to the flat rhombus is below this share of E_S changes no result by a rounding unit
#: (t_F and the rates move by about half that share): it is taken as 0, so that forces down to the smallest
#: subnormal give the frictionless answers instead of overflowing E_S / (2 F1 L1).
NEGLIGIBLE_WORK = 2.0**-64


def _screen(E_S, F1, F2, L1):
    """(F1, F2, E_S, bad) for the kernels: negligible friction set to 0, cases outside the floating-point
    range marked ``bad`` and replaced by a harmless case (their outputs are then set to NaN). One compiled pass
    (:func:`quickrelease.batch._fast.screen_flags`); the inputs themselves come back where no case needs either."""
    from . import _fast

    bad = np.empty(E_S.shape, dtype=bool)
    tiny = np.empty(E_S.shape, dtype=bool)
    if _fast.screen_flags(E_S, F1, F2, L1, NEGLIGIBLE_WORK, bad, tiny) == 0:
        return F1, F2, E_S, bad
    F1, F2, E_S = (np.where(tiny | bad, 0.0, F1), np.where(tiny | bad, 0.0, F2), np.where(bad, 1.0, E_S))
    return F1, F2, E_S, bad


@dataclass(frozen=True)
class BatchIdentification(_Result):
    """Friction identified from many stop observations (Eq. 11-13)."""

    F1: np.ndarray
    """Hinge friction [N] (NaN where status != 0)."""
    F2: np.ndarray
    """Rail friction [N] (NaN where status != 0)."""
    F1_max: np.ndarray
    """F1* (Eq. 11) [N]."""
    F2_max: np.ndarray
    """F2* (Eq. 12) [N]."""
    stop_time_min: np.ndarray
    """t_F(F1 = 0) [s]: the fastest stop the line of Eq. 13 allows."""
    stop_time_max: np.ndarray
    """t_F(F1 = F1*) [s]: the slowest."""
    status: np.ndarray
    """0 ok, else the reason (see :data:`IDENTIFY_STATUS`)."""
    iterations: np.ndarray
    """Halley iterations used (Newton's where Halley's step is not safe)."""

    @property
    def feasible(self) -> np.ndarray:
        return self.status == 0

    def reasons(self) -> dict[str, int]:
        """How many cases ended with each status, by message."""
        codes, counts = np.unique(self.status, return_counts=True)
        return {IDENTIFY_STATUS[int(c)]: int(n) for c, n in zip(codes, counts, strict=True)}


def _chunks(n: int, chunk: int):
    for start in range(0, n, chunk):
        yield slice(start, min(start + chunk, n))


#: The places the kernels run: ``numpy`` (this process's CPU cores: the compiled kernels of :mod:`._fast`) or
#: ``gpu`` (a CUDA GPU through CuPy: :mod:`._gpu`, ``pip install 'quickrelease[gpu]'``).
BACKENDS = ("numpy", "gpu")


def _array_module(backend: str):
    """None for the numpy backend, CuPy for ``gpu`` (checked before any work: QuickReleaseError naming the
    ``[gpu]`` extra when CuPy or a CUDA device is missing); ParameterError for any other name."""
    if backend == "numpy":
        return None
    if backend != "gpu":
        raise ParameterError("backend", backend, "'numpy' or 'gpu'")
    from . import _gpu

    _gpu.require_gpu()
    return _gpu.array_module()


def _on_device(xp, kernel, *arrays, **options):
    """``kernel(xp, *arrays on the device, **options)`` with its results (a tuple or a dict) copied back."""
    from ._gpu import device_chunk, to_host

    options.setdefault("chunk", device_chunk(xp))
    res = kernel(xp, *(xp.asarray(a) for a in arrays), **options)
    if isinstance(res, dict):
        return {key: to_host(v) for key, v in res.items()}
    return tuple(to_host(v) for v in res)


def stop_time(E_S, alpha0, F1, F2, c=2.0 / 3.0, m1=None, m2=None, L1=None, *, chunk: int = CHUNK,
              backend: str = "numpy") -> BatchStop:
    """Stop time t_F and final angle alpha_F of many releases (Eq. 8 and 10).

    Parameters broadcast: E_S [J], alpha0 [rad], F1, F2 [N], c [-], m1, m2 [kg], L1 [m] (the paper's
    device where not given). Cases must be valid (E_S > 0, alpha0 in (0, pi/2), F1, F2 >= 0); they are
    not checked one by one here (see :func:`quickrelease.simulate` for checked single releases).
    ``backend``: ``"numpy"`` (the compiled CPU kernels, all cores) or ``"gpu"`` (CuPy on a CUDA GPU, float64, the
    same formulas, within 1e-13 relative of the CPU's: ``pip install 'quickrelease[gpu]'``).
    """
    xp = _array_module(backend)
    m1, m2, L1 = _paper_defaults(m1, m2, L1)
    shape, (E_S, alpha0, F1, F2, c, m1, m2, L1) = _flat(E_S, alpha0, F1, F2, c, m1, m2, L1)
    if xp is None:  # screened chunk by chunk on the threads
        t, aF, code = _outputs(E_S.size)
        _on_threads(_screened_chunk, E_S.size, (E_S, alpha0, F1, F2, c, m1, m2, L1), (t, aF, code))
    else:
        from . import _gpu

        F1, F2, E_S, bad = _screen(E_S, F1, F2, L1)
        t, aF, code = _on_device(xp, _gpu.stop_arrays, E_S, alpha0, F1, F2, c * m1 / m2, m2, L1)
        if bad.any():
            t[bad], aF[bad] = np.nan, np.nan
    return BatchStop(t.reshape(shape), aF.reshape(shape), code.reshape(shape))


#: Cases per chunk of the threaded stop-time path (:func:`_stop_arrays`): small enough that the threads, taking
#: the next chunk as they finish one, end together (a few per thread), large enough that a chunk costs 1-2 ms.
THREAD_CHUNK = 16384


def _stop_chunk(E_S, alpha0, F1, F2, k, m2, L1, t, aF, code):
    """One chunk of :func:`_stop_arrays`, in place: the compiled loop (sin and cos of alpha0 by libm, which numpy
    calls too), then a friction stop's alpha_F = min(alpha0 + max(atan2(N, D), 0), pi/2) with numpy's arctan2, as
    the single-case solver computes it (numpy's vectorised arctan2 and libm's atan2 differ in the last bit of 3% of
    angles), the rest of that formula compiled (every step releases the GIL)."""
    from . import _fast

    N, D, _ = _scratch(E_S.size)
    _fast.stop_kernel_sides(E_S, alpha0, F1, F2, k, m2, L1, *_fast.rules(), *_fast.tier_constants(), t, aF, N, D, code)
    _fast.friction_angles(np.arctan2(N, D, out=N), alpha0, aF)


_local = threading.local()


def _scratch(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Three work arrays of n values, this thread's, reused from chunk to chunk: a chunk's arrays are too large for
    malloc's heap (each would be mapped and unmapped again, and unmapping memory interrupts every core the process
    runs on, which made two threads' speed-up vary between 1.6x and 1.9x)."""
    buf = getattr(_local, "scratch", None)
    if buf is None or buf.shape[1] < n:
        buf = _local.scratch = np.empty((3, max(n, THREAD_CHUNK)))
    return buf[0, :n], buf[1, :n], buf[2, :n]


def _screened_chunk(E_S, alpha0, F1, F2, c, m1, m2, L1, t, aF, code):
    """One chunk of :func:`stop_time` from the raw inputs, in place: :func:`_screen` and ``k = c m1 / m2`` on the
    chunk (so that they share the threads too), :func:`_stop_chunk`, and NaN where a case is out of range."""
    F1, F2, E_S, bad = _screen(E_S, F1, F2, L1)
    k = _scratch(E_S.size)[2]
    np.divide(np.multiply(c, m1, out=k), m2, out=k)  # c * m1 / m2, rounded as written
    _stop_chunk(E_S, alpha0, F1, F2, k, m2, L1, t, aF, code)
    if bad.any():
        t[bad], aF[bad] = np.nan, np.nan


def _on_threads(chunk_fn, n: int, inputs, outputs) -> None:
    """``chunk_fn(*inputs[sl], *outputs[sl])`` for the chunks sl of at most :data:`THREAD_CHUNK` cases (at least 8 a
    thread where there are enough cases), on numba's current number of threads (``numba.set_num_threads``;
    :func:`quickrelease.using_threads`), a chunk at a time per thread. Each case is computed alone, so the results
    do not depend on the number of threads, bit for bit."""
    import numba

    threads = numba.get_num_threads()
    # at least 8 chunks a thread where n allows (chunks of 1024 cases at the least), so that they end together
    size = min(THREAD_CHUNK, max(1024, -(-n // (8 * threads))))
    threads = min(threads, -(-n // size))
    args = [tuple(a[sl] for a in inputs) + tuple(o[sl] for o in outputs) for sl in _chunks(n, size)]
    if threads <= 1:
        for a in args:
            chunk_fn(*a)
    else:  # a pool per call (a few threads started for at least two chunks of work; nothing left to a fork)
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(threads, thread_name_prefix="quickrelease-stop") as pool:
            list(pool.map(lambda a: chunk_fn(*a), args))


def _outputs(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return np.empty(n), np.empty(n), np.empty(n, dtype=np.int8)


def _stop_arrays(E_S, alpha0, F1, F2, k, m2, L1, chunk):
    """Flat screened arrays in, (t_F, alpha_F, code) out: :func:`_stop_chunk` on the threads (:func:`_on_threads`)."""
    out = _outputs(E_S.size)
    _on_threads(_stop_chunk, E_S.size, (E_S, alpha0, F1, F2, k, m2, L1), out)
    return out


def _peak_head_velocity(E_S, alpha0, alpha_end, A, B, k, m2, n_samples: int = 8, newton: int = 5):
    """Peak of u_dot = sqrt(sin^2(a) K(a) / (m2 (k + sin^2 a))) over [alpha0, alpha_end] [m/s].

    Samples the interval, then Newton's method on d ln(g)/d alpha from the best sample, with
    g = sin^2(a) K(a) / (k + sin^2 a) and K = E_S - W_F (Eq. 9); the endpoints are kept as candidates. One
    implementation for every backend: the array-module one of :mod:`quickrelease.batch._gpu`, here with numpy.
    """
    from . import _gpu

    return _gpu._peak_head_velocity(np, E_S, alpha0, alpha_end, A, B, k, m2, n_samples, newton)


#: Angles sampled for the peak accelerations, to pick the best sample; the maximum is then the root of the
#: jerk bracketed by its neighbours (``_kernels.refine_peak``), to about 1e-13 relative.
N_PEAK = 65


def _peak_accelerations(E_S, alpha0, alpha_end, F1, F2, k, m2, L1, n: int = N_PEAK):
    """Peaks of |u_ddot| and |v_ddot| over [alpha0, alpha_end]: the best of n angles, then the maximum at the
    root of the jerk (d/dt of the acceleration, located in alpha: ``_kernels.refine_peak``) bracketed by the
    best sample and a neighbour (the end point is the state just before the stop).

    The numpy reference of the compiled ``_fast.peak_accel_kernel`` used by :func:`release` (a test checks
    they agree)."""
    x = np.linspace(0.0, 1.0, n)
    a = alpha0[:, None] + (alpha_end - alpha0)[:, None] * x
    s, co = np.sin(a), np.cos(a)
    sa0, ca0 = np.sin(alpha0)[:, None], np.cos(alpha0)[:, None]
    K = E_S[:, None] - 2.0 * F1[:, None] * L1[:, None] * (s - sa0) - 4.0 * F2[:, None] * L1[:, None] * (ca0 - co)
    d = k[:, None] + s * s
    rate2 = np.maximum(K, 0.0) / (m2[:, None] * L1[:, None] ** 2 * d)  # Eq. 10, squared
    acc = -rate2 * s * co / d - (2.0 * F2[:, None] * s + F1[:, None] * co) / (m2[:, None] * L1[:, None] * d)
    out = []
    for which, values in enumerate((L1[:, None] * (co * rate2 + s * acc), L1[:, None] * (-s * rate2 + co * acc))):
        mag = np.abs(values)
        best = np.argmax(mag, axis=1)
        peak = mag[np.arange(mag.shape[0]), best]
        for i, j in enumerate(best):
            h = (alpha_end[i] - alpha0[i]) / (n - 1)
            args = (E_S[i], math.sin(alpha0[i]), math.cos(alpha0[i]), 2.0 * F1[i] * L1[i], 4.0 * F2[i] * L1[i],
                    F1[i], F2[i], k[i], m2[i], L1[i], which)
            for lo, hi in ((j - 1, j), (j, j + 1)):
                if 0 <= lo and hi < n:
                    peak[i] = max(peak[i], _kernels.refine_peak(alpha0[i] + lo * h, alpha0[i] + hi * h, *args))
        out.append(peak)
    return out


def release(E_S, alpha0, F1, F2, c=2.0 / 3.0, m1=None, m2=None, L1=None, *, chunk: int = CHUNK,
            backend: str = "numpy") -> BatchRelease:
    """Release envelope of many cases: t_F, alpha_F, u_F, v_F, initial and peak velocities and accelerations.

    Same inputs (and ``backend``) as :func:`stop_time`.
    """
    xp = _array_module(backend)
    m1, m2, L1 = _paper_defaults(m1, m2, L1)
    shape, (E_S, alpha0, F1, F2, c, m1, m2, L1) = _flat(E_S, alpha0, F1, F2, c, m1, m2, L1)
    n = E_S.size
    out = {name: np.empty(n) for name in ("stop_time", "alpha_final", "u_final", "v_final", "alpha_dot0",
                                          "peak_u_dot", "peak_v_dot", "peak_u_ddot", "peak_v_ddot")}
    code = np.empty(n, dtype=np.int8)
    k = c * m1 / m2
    F1, F2, E_S, bad = _screen(E_S, F1, F2, L1)
    if xp is not None:
        from . import _gpu

        res = _on_device(xp, _gpu.release_arrays, E_S, alpha0, F1, F2, k, m2, L1)
        code[:] = res.pop("stopped_by")
        for name, v in res.items():
            out[name][:] = v
    else:
        _release_cpu(E_S, alpha0, F1, F2, k, m2, L1, chunk, out, code)
    creeps = code == 2  # t_F = inf by the classifier (STOPPED_BY 2): a result, not an overflow
    for name, v in out.items():  # a result that overflows is flagged too, never left as a silent inf or NaN
        finite = np.isfinite(v) | (creeps & (v == np.inf)) if name == "stop_time" else np.isfinite(v)
        bad |= ~finite
    for v in out.values():
        v[bad] = np.nan
    out["status"] = bad.astype(np.int8)
    res = {key: v.reshape(shape) for key, v in out.items()}
    return BatchRelease(stopped_by=code.reshape(shape), **res)


def _release_cpu(E_S, alpha0, F1, F2, k, m2, L1, chunk, out, code):
    """The envelope of :func:`release` on the CPU, into ``out`` and ``code`` (flat arrays)."""
    n = E_S.size
    t, aF_all, code[:] = _stop_arrays(E_S, alpha0, F1, F2, k, m2, L1, chunk)
    out["stop_time"][:] = t
    out["alpha_final"][:] = aF_all
    for sl in _chunks(n, chunk):
        aF = aF_all[sl]
        # the sweep from the cancellation-free closed form of Eq. 8 (not aF - alpha0: aF is rounded)
        delta = dynamics.sweep_angle(E_S[sl], alpha0[sl], F1[sl], F2[sl], L1[sl])
        half_sum = alpha0[sl] + 0.5 * delta
        sigma_m = np.sin(0.5 * delta)
        out["u_final"][sl] = 2.0 * L1[sl] * np.sin(half_sum) * sigma_m  # Table 4, cancellation-free
        # cos of the half sum as the sine of its distance to pi/2 (cos(half_sum) would keep the rounding of the
        # sum, 1.1e-16 rad, relative to itself: 1e-8 of v_F for a stop 1e-8 rad from pi/2)
        out["v_final"][sl] = 2.0 * L1[sl] * np.sin(dynamics.limit_sweep(alpha0[sl]) - 0.5 * delta) * sigma_m
        sa0 = np.sin(alpha0[sl])
        ad0 = np.sqrt(E_S[sl] / (m2[sl] * L1[sl] ** 2 * (k[sl] + sa0 * sa0)))  # Eq. 6
        out["alpha_dot0"][sl] = ad0
        out["peak_v_dot"][sl] = L1[sl] * np.cos(alpha0[sl]) * ad0  # v_dot decreases from release on
        out["peak_u_dot"][sl] = _peak_head_velocity(E_S[sl], alpha0[sl], aF, 2.0 * F1[sl] * L1[sl],
                                                    4.0 * F2[sl] * L1[sl], k[sl], m2[sl])
    from . import _fast

    _fast.peak_accel_kernel(E_S, alpha0, aF_all, F1, F2, k, m2, L1, N_PEAK, out["peak_u_ddot"], out["peak_v_ddot"])


def identify(alpha0, alpha_final, stop_time, E_S, c=2.0 / 3.0, m1=None, m2=None, L1=None, *,
             chunk: int = CHUNK, tol: float = 1e-14, max_iter: int = 40, backend: str = "numpy") -> BatchIdentification:
    """Identify F1, F2 from many stop observations (Eq. 11-13), vectorized.

    On the line of Eq. 13 every case stops at alpha_final; with lambda = F1/F1*, the remaining energy
    is ``K = E_S w^2 (lambda a + (1 - lambda) b)`` at the quadrature nodes, where a and b are the
    normalized remaining energies of pure hinge and pure rail friction. The nodes, a and b do not
    depend on lambda, so each step costs one square root and one division per node. t(lambda) is increasing
    and convex; Halley's method from lambda = 1 (its first two derivatives from the same sums) converges in 3-4
    steps, Newton's step taken where Halley's denominator is not safely positive.

    ``backend``: as for :func:`stop_time` (on the GPU, lambda within ``1e-13 + 8 eps t_F / (t_hi - t_lo)`` of the
    CPU's: the rounding floor of an observation whose t_F barely changes along the line).

    Returns
    -------
    BatchIdentification
        Infeasible or invalid cases have NaN F1, F2 and a nonzero ``status``.
    """
    xp = _array_module(backend)
    m1, m2, L1 = _paper_defaults(m1, m2, L1)
    shape, (alpha0, aF, tF, E_S, c, m1, m2, L1) = _flat(alpha0, alpha_final, stop_time, E_S, c, m1, m2, L1)
    n = alpha0.size
    names = ("F1", "F2", "F1_max", "F2_max", "stop_time_min", "stop_time_max")
    out = {name: np.full(n, np.nan) for name in names}
    status = np.zeros(n, dtype=np.int8)
    iters = np.zeros(n, dtype=np.int16)
    finite = np.isfinite(alpha0) & np.isfinite(aF) & np.isfinite(tF) & np.isfinite(E_S)
    with np.errstate(invalid="ignore"):
        good_pos = finite & (E_S > 0) & (tF > 0) & (c > 0) & (m1 > 0) & (m2 > 0) & (L1 > 0)
        status[~good_pos] = 5
        status[good_pos & ~((alpha0 > 0) & (alpha0 < HALF_PI))] = 4
        status[(status == 0) & ~((aF > alpha0) & (aF < HALF_PI))] = 3
    k = c * m1 / m2
    from . import _fast

    lam = np.full(n, np.nan)
    if xp is not None:
        from . import _gpu

        ok = status == 0
        res = _on_device(xp, _gpu.identify_arrays, alpha0[ok], aF[ok], tF[ok], E_S[ok], k[ok], m2[ok], L1[ok],
                         tol=tol, max_iter=max_iter)
        lam[ok], status[ok], iters[ok] = res["lam"], res["status"], res["iterations"]
        for name in ("F1_max", "F2_max", "stop_time_min", "stop_time_max"):
            out[name][ok] = res[name]
    else:
        x16, w16, x24, w24 = _fast.rules()
        _fast.identify_kernel(alpha0, aF, tF, E_S, k, m2, L1, x16, w16, x24, w24, *_fast.tier_constants(), tol,
                              max_iter, lam, out["F1_max"], out["F2_max"], out["stop_time_min"], out["stop_time_max"],
                              status, iters)
    out["F1"] = lam * out["F1_max"]
    out["F2"] = (1.0 - lam) * out["F2_max"]
    bad = status != 0
    out["F1"][bad] = np.nan
    out["F2"][bad] = np.nan
    return BatchIdentification(**{k_: v.reshape(shape) for k_, v in out.items()},
                               status=status.reshape(shape), iterations=iters.reshape(shape))


def _newton_on_line(x, wt, sigma_m, sA, cA, c1_0, c2_0, k, pref, target, tol, max_iter):
    """Newton's method in lambda = F1/F1* on fixed nodes (nodes-first arrays, in place where it counts)."""
    sigma = (x * x)[:, None] * sigma_m
    q = np.sqrt(1.0 - sigma * sigma)
    sin_alpha = sA * (1.0 - 2.0 * sigma * sigma) - cA * 2.0 * sigma * q
    P = wt[:, None] * np.sqrt(k + sin_alpha * sin_alpha) / q
    a = (cA * q + sA * sigma) / c1_0  # pure hinge friction: (sin aF - sin alpha) / (sin aF - sin a0) / w^2
    b = (sA * q - cA * sigma) / c2_0  # pure rail friction: (cos alpha - cos aF) / (cos a0 - cos aF) / w^2
    d = a - b
    Pd = P * d
    t_lo = pref * np.einsum("ij,ij->j", P, 1.0 / np.sqrt(b))  # lambda = 0: F1 = 0
    t_hi = pref * np.einsum("ij,ij->j", P, 1.0 / np.sqrt(a))  # lambda = 1: F1 = F1*
    feasible = (target >= t_lo) & (target <= t_hi)
    lam = np.ones(sigma_m.size)
    lam[target < t_lo] = 0.0  # within rounding of F1 = 0: that end (the caller decides what is within rounding)
    iters = np.zeros(sigma_m.size, dtype=np.int16)
    active = feasible & (t_hi > target)
    H = np.empty_like(P)
    R = np.empty_like(P)
    for _ in range(max_iter):
        if not np.any(active):
            break
        np.multiply(d, lam, out=H)
        H += b
        np.sqrt(H, out=R)
        np.divide(1.0, R, out=R)  # h^(-1/2)
        t_val = pref * np.einsum("ij,ij->j", P, R)
        np.multiply(R, R, out=H)
        H *= R  # h^(-3/2)
        slope = -0.5 * pref * np.einsum("ij,ij->j", Pd, H)
        new = np.clip(lam - (t_val - target) / slope, 0.0, 1.0)
        # converged: lambda final to tol of its range [0, 1] (F1 to tol F1*), or to its rounding floor
        done = np.abs(new - lam) <= np.maximum(tol, 8.0 * np.finfo(float).eps * t_val / np.abs(slope))
        lam = np.where(active, new, lam)
        iters += active
        active &= ~done
    return lam, t_lo, t_hi, iters


def _identify_chunk(alpha0, aF, tF, E_S, k, m2, L1, tol, max_iter) -> dict[str, Any]:
    """The numpy reference of the compiled ``_fast.identify_kernel`` (Newton's method on the full graded rule of
    ``_kernels``): tests check the two agree."""
    # sines, cosines, the normalizers c1_0, c2_0, F1* and F2* (Eq. 11-12), the tiers' ratios and the prefactor: the
    # setup of every back-end (the tiers as for the stop-time kernel)
    sA, cA, sigma_m, c1_0, c2_0, F1_max, F2_max, end_ratio, mass_sq, pref = _identify_setup.for_arrays(np)(
        alpha0, aF, E_S, k, m2, L1)
    tier = _kernels.tier_of(end_ratio, mass_sq)
    lam = np.empty(alpha0.size)
    t_lo = np.empty(alpha0.size)
    t_hi = np.empty(alpha0.size)
    iters = np.zeros(alpha0.size, dtype=np.int16)
    rules = {0: gauss_unit(_kernels.N_NODES), 1: gauss_unit(_kernels.N_NODES_MASS), 2: graded_unit()}
    for tr, (x, wt) in rules.items():
        m = tier == tr
        if not np.any(m):
            continue
        sub = slice(None) if m.all() else m
        lm, lo, hi, it = _newton_on_line(x, wt, sigma_m[sub], sA[sub], cA[sub], c1_0[sub], c2_0[sub], k[sub],
                                         pref[sub], tF[sub], tol, max_iter)
        lam[sub], t_lo[sub], t_hi[sub], iters[sub] = lm, lo, hi, it
    # an observation within rounding of an end of the feasible interval is that end (lam 0 or 1, set above)
    # (on either side of it: the end is the solution there, to within what rounding can tell)
    slack_lo = _kernels.feasible_slack(t_lo, alpha0, aF, 0.0)
    slack_hi = _kernels.feasible_slack(t_hi, alpha0, aF, 1.0)  # (the F1* end's sensitivity widens it outwards only)
    at_hi = (np.abs(tF - t_hi) <= _kernels.feasible_slack(t_hi, alpha0, aF, 0.0)) \
        | ((tF > t_hi) & (tF <= t_hi + slack_hi))
    lam = np.where(np.abs(tF - t_lo) <= slack_lo, 0.0, np.where(at_hi, 1.0, lam))
    status = np.where(tF < t_lo - slack_lo, 1, np.where(tF > t_hi + slack_hi, 2, 0)).astype(np.int8)
    lam = np.where(status == 0, lam, np.nan)
    return {"F1": lam * F1_max, "F2": (1.0 - lam) * F2_max, "F1_max": F1_max, "F2_max": F2_max,
            "stop_time_min": t_lo, "stop_time_max": t_hi, "status": status, "iterations": iters}
