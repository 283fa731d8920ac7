"""The batch kernels written once against an array module ``xp``: CuPy on a GPU, numpy on the CPU (issue 12, item 4).

The stop time (Eq. 8-10), the release envelope (Table 4, Eq. 6) and the identification on the line of Eq. 13 of
:mod:`quickrelease.batch`, with the formulas, node rules, tier criteria and graded panels of the compiled CPU kernels
(:mod:`quickrelease.batch._fast`, from :mod:`quickrelease.device._kernels`), vectorised across cases instead of
looped over them:

* Only what numpy and CuPy share: ``xp.sin``, ``cos``, ``sqrt``, ``arctan2``, ``log``, ``ceil``, ``where``,
  ``minimum``, ``maximum``, ``abs``, boolean masks and integer gathers, arithmetic. The pure functions of
  :mod:`quickrelease.device.dynamics` that the setup calls (``amplitude_terms``, ``limit_margin_terms``,
  ``creeps_terms``,
  ``limit_sweep``, ``_stop_terms``, ``sweep_sides``) and ``_kernels.feasible_slack`` are arithmetic and numpy
  ufuncs (``np.sqrt``, ``np.maximum``, ``np.abs``, ``np.cos``), which CuPy arrays take through
  ``__array_ufunc__``: they are called as they are, one definition of the classifier and of Eq. 8 for every backend
  (a test checks they call nothing else). The identification's setup is
  :func:`quickrelease.batch._identify_setup.identify_setup`, the function the compiled kernel calls, bound to ``xp``'s
  ``sin``, ``cos`` and ``sqrt``. ``np.where``, ``np.clip``, ``np.argmax`` and
  ``_kernels.tier_of`` are not ufuncs and are not called (the tiers are re-stated below with ``xp.where``).
* Float64 throughout. No Python loop over cases: loops run over quadrature nodes, graded panels, Halley steps and
  Illinois steps, each a vectorised pass over the cases still concerned.
* Partitioned by tier: the cases of each (regime, tier) are gathered and run as one pass (16 nodes, 24 nodes, or the
  graded rule with only the panels a case needs: panel j of a case is computed only for the cases whose
  :func:`panel_counts` reach j, as ``_fast._graded_sum`` does).
* In chunks of ``chunk`` cases, so that memory stays bounded (node arrays of n_nodes x chunk; the graded tier in
  sub-chunks of the same number of node values).

With ``xp = numpy`` the very same code runs on the CPU: that is how the tests exercise it on a machine without a GPU
(tests/test_gpu.py: against the compiled kernels to 1e-13 relative, and against mpmath), and ``quickrelease bench``
measures its CPU throughput for reference. The compiled kernels sum the nodes in another order (fastmath
reassociation), so the two agree to a few ulps, not bit for bit; a case within rounding of a tier's threshold may
take the neighbouring rule on one and not the other, which both keep within 1e-12 of the exact value.

:func:`gpu_available` says whether CuPy is importable and sees a CUDA device; :func:`require_gpu` raises
:class:`~quickrelease.errors.QuickReleaseError` (one line, naming the ``[gpu]`` extra) when not.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from ..device import _kernels, dynamics
from ..errors import QuickReleaseError
from . import _identify_setup

__all__ = ["gpu_available", "require_gpu", "array_module", "device_chunk", "stop_arrays", "release_arrays",
           "identify_arrays", "panel_counts", "INSTALL"]

HALF_PI = 0.5 * math.pi
#: Cases per chunk: node arrays of n_nodes x CHUNK float64 (24 x 2^20 x 8 B = 200 MB on a GPU) [-].
CHUNK = 1 << 20
#: Device memory one case takes in a chunk's arrays, rounded up: measured on the numpy path with tracemalloc, about
#: 1.05 kB a case for the stop time and the release envelope and 1.9 kB for the identification [B].
BYTES_PER_CASE = 2048
#: The largest chunk :func:`device_chunk` picks: on an H200 (2026-11-26, 2e7 stop times) 2^20 cases a chunk ran
#: 3.8e7 cases/s and 2^22 ran 1.15e8 (the kernels' launches amortised over more cases) [-].
MAX_CHUNK = 1 << 22
#: What to install for the GPU backend.
INSTALL = "pip install 'quickrelease[gpu]'"
#: Grading steps past a near-singularity's distance that the graded rule goes on panelling (as ``_fast``).
GRADED_REACH = 1
EPS = 2.220446049250313e-16


@lru_cache(maxsize=1)
def _device_count() -> int:
    import cupy

    return int(cupy.cuda.runtime.getDeviceCount())


def gpu_available() -> bool:
    """True where CuPy imports and sees at least one CUDA device (no device, no driver or no CuPy: False)."""
    try:
        return _device_count() > 0
    except Exception:  # ImportError, or CUDARuntimeError / a missing driver library: no usable GPU
        return False


def _cupy_installed() -> bool:
    """True where CuPy can be found (imported or not); a broken or half-installed one counts as missing."""
    from importlib.util import find_spec

    try:
        return find_spec("cupy") is not None
    except (ImportError, ValueError):
        return False


def require_gpu() -> None:
    """Raise QuickReleaseError (one line) unless :func:`gpu_available`: what is missing and how to install it."""
    if not _cupy_installed():
        raise QuickReleaseError(f"the gpu backend needs cupy (not installed): {INSTALL}")
    if not gpu_available():
        raise QuickReleaseError("the gpu backend needs a CUDA device: CuPy is installed but found none "
                                "(use --backend numpy)")


def array_module():
    """CuPy (the GPU backend's array module); :func:`require_gpu` first."""
    import cupy

    return cupy


def synchronize(xp) -> None:
    """Wait for the device's queued work (timing): CuPy's current device; nothing for numpy."""
    cuda = getattr(xp, "cuda", None)
    if cuda is not None:
        cuda.Device().synchronize()


def device_name() -> tuple[str, str]:
    """(the current CUDA device's name, CuPy's version)."""
    import cupy

    props = cupy.cuda.runtime.getDeviceProperties(cupy.cuda.Device().id)
    name = props["name"].decode() if isinstance(props["name"], bytes) else str(props["name"])
    return name, cupy.__version__


def device_chunk(xp) -> int:
    """Cases per chunk on ``xp``'s device: the largest power of two from :data:`CHUNK` to :data:`MAX_CHUNK` whose
    arrays (:data:`BYTES_PER_CASE` a case) take at most a quarter of the device's free memory; :data:`CHUNK` for
    numpy (host memory, where a larger chunk gains nothing)."""
    cuda = getattr(xp, "cuda", None)
    if cuda is None:
        return CHUNK
    free = cuda.runtime.memGetInfo()[0]
    chunk = CHUNK
    while chunk < MAX_CHUNK and 2 * chunk * BYTES_PER_CASE <= free / 4:
        chunk *= 2
    return chunk


def to_host(a) -> np.ndarray:
    """A numpy array of ``a`` (a CuPy array is copied off the device)."""
    get = getattr(a, "get", None)
    return get() if get is not None else np.asarray(a)


def _gauss(xp, n):
    x, w = _kernels.gauss_unit(n)
    return xp.asarray(x), xp.asarray(w)


def _tier(xp, ratio, msq):
    """``_kernels.tier_of`` with xp.where: 2 graded, 1 the 24-node rule, 0 16 nodes [-]."""
    hard = (ratio < _kernels.HARD_RATIO) | (msq < _kernels.MASS_HARD ** 2)
    near = (ratio < _kernels.NEAR_RATIO) | (msq < _kernels.MASS_RATIO ** 2)
    return xp.where(hard, 2, xp.where(near, 1, 0))


def panel_counts(xp, distance):
    """Graded panels towards an end whose near-singularity lies ``distance`` from it (``_fast._panel_count``):
    ``ceil(log(2 d) / log(GRADING)) + GRADED_REACH`` clipped to [0, N_PANELS]; N_PANELS where d is not > 0 [-]."""
    panels = _kernels.N_PANELS
    with np.errstate(divide="ignore", invalid="ignore"):
        j = xp.ceil(xp.log(2.0 * xp.where(distance > 0.0, distance, 1.0)) / math.log(_kernels.GRADING)) + GRADED_REACH
    j = xp.where(distance > 0.0, j, panels)
    return xp.minimum(xp.maximum(xp.where(j == j, j, 0.0), 0.0), panels).astype(xp.int64)


def _panel_edges():
    """The upper edges r^j / 2 of the graded panels, by repeated multiplication as ``_fast._graded_sum`` [-]."""
    his = [0.5]
    for _ in range(_kernels.N_PANELS):
        his.append(his[-1] * _kernels.GRADING)
    return his


def _graded_panels(xp, jl, jr):
    """(j, side, index of the cases, start, width) of every panel the cases need: towards w = 0 the panels
    [r^(j+1)/2, r^j/2] for j < jl and [0, r^jl/2], towards w = 1 their mirror images (``_fast._graded_sum``)."""
    his = _panel_edges()
    for counts, right in ((jl, False), (jr, True)):
        top = int(xp.max(counts)) if counts.size else -1
        for j in range(top + 1):
            idx = xp.nonzero(counts >= j)[0]
            if idx.size == 0:
                continue
            hi = his[j]
            lo = xp.where(counts[idx] > j, hi * _kernels.GRADING, 0.0)
            width = hi - lo
            start = 1.0 - hi if right else lo
            yield idx, start, width


# -- stop time ------------------------------------------------------------------------------------------------------

def _setup(xp, E, a0, F1, F2, k, m2, L1):
    """Per-case constants of ``_fast._stop_one``, vectorised: dict of arrays (regime 0 friction, 1 limit, 2 creep)."""
    with np.errstate(all="ignore"):
        sa0 = xp.sin(a0)
        ca0 = xp.cos(a0)
        A = 2.0 * F1 * L1
        B = 4.0 * F2 * L1
        R = dynamics.amplitude_terms(A, B)  # sqrt(A^2 + B^2) scaled by powers of two, as the CPU kernels
        Kl = dynamics.limit_margin_terms(E, A, B, sa0, ca0)
        creep = dynamics.creeps_terms(Kl, E, A, B)
        to_limit = dynamics.limit_sweep(a0)
        limit = (Kl > 0.0) & ~creep
        s0, cv, e, s, cb = dynamics._stop_terms(E, A, B, R, sa0, ca0)
        N, D = dynamics.sweep_sides(s0, cv, e, s, cb)
        g = N * sa0 - D * ca0
        angle = xp.arctan2(N, D)
        flat = xp.where(xp.abs(g) <= 1e-9, angle >= to_limit, g > 0.0)
        geo = limit | creep
        flat = flat & ~geo
        fric = ~geo & ~flat
        sm_lim = xp.sin(0.5 * to_limit)
        r = xp.sqrt(N * N + D * D)
        sm_fric = xp.where(N > 0.0, N / xp.sqrt(2.0 * r * (r + D)), 0.0)
        s = xp.where(flat, A / R, s)
        cb = xp.where(flat, B / R, cb)
        sm = xp.where(fric, sm_fric, sm_lim)
        sA = xp.where(geo, 1.0, (B * cb + A * s) / R)
        cA = xp.where(geo, 0.0, (A * cb - B * s) / R)
        cb = xp.where(geo, 0.0, cb)
        s = xp.where(geo, 1.0, s)
        qm = xp.sqrt(1.0 - sm * sm)
        ratio_lim = Kl / (Kl + 2.0 * A * sm * sm + 2.0 * B * sm * qm)
        ratio = xp.where(geo, ratio_lim, cb / (cb * qm + s * sm))
        pref_lim = 4.0 * sm * L1 * xp.sqrt(m2)
        pref = xp.where(geo, pref_lim, 4.0 * L1 * xp.sqrt(sm) * xp.sqrt(m2) / xp.sqrt(2.0 * R))
        msq = xp.where(sm > 0.0, (k + sa0 * sa0) / (4.0 * sm * sm), xp.inf)
        # alpha_F: numpy's min(alpha0 + max(atan2(N, D), 0), pi/2) for a friction stop (as batch._stop_chunk)
        aF = xp.where(fric, xp.minimum(a0 + xp.maximum(angle, 0.0), HALF_PI),
                      xp.where(flat, xp.minimum(a0 + to_limit, HALF_PI), HALF_PI))
        delta = xp.where(geo, to_limit, xp.minimum(xp.maximum(angle, 0.0), to_limit))  # dynamics.sweep_angle
    regime = xp.where(creep, 2, xp.where(limit, 1, 0))
    return {"regime": regime, "tier": _tier(xp, ratio, msq), "ratio": ratio, "msq": msq, "sm": sm, "sA": sA,
            "cA": cA, "cb": cb, "s": s, "Kl": Kl, "A": A, "B": B, "k": k, "pref": pref, "aF": aF, "delta": delta,
            "sa0": sa0, "ca0": ca0}


def _friction_panel(xp, x, w, start, width, c):
    """sum_j w_j sqrt((k + sin^2 alpha) / (C q^2)) over the nodes start + width x_j, times width: the friction
    integrand of ``_kernels`` (sigma = sigma_m u^2, C = cos(a - phi) q + sin(a - phi) sigma), per case [-]."""
    u = start + width * x[:, None]
    sg = (u * u) * c["sm"]
    s2 = sg * sg
    q2 = 1.0 - s2
    q = xp.sqrt(q2)
    sal = c["sA"] * (1.0 - 2.0 * s2) - c["cA"] * 2.0 * sg * q
    C = c["cb"] * q + c["s"] * sg
    return (w @ xp.sqrt((c["k"] + sal * sal) / (C * q2))) * width


def _limit_panel(xp, x, w, start, width, c):
    """sum_j w_j u_j sqrt(k + sin^2 alpha) / sqrt(K q^2) over the nodes u_j = start + width x_j, times width: the
    geometric-limit integrand (K = K_lim + 2 A sigma^2 + 2 B sigma q), per case [-]."""
    u = start + width * x[:, None]
    s = (u * u) * c["sm"]
    s2 = s * s
    q2 = 1.0 - s2
    sal = 1.0 - 2.0 * s2
    K = c["Kl"] + 2.0 * c["A"] * s2 + 2.0 * c["B"] * s * xp.sqrt(q2)
    return (w @ (u * xp.sqrt(c["k"] + sal * sal) / xp.sqrt(K * q2))) * width


def _take(c, idx):
    return {key: v[idx] for key, v in c.items()}


def _quadrature(xp, c, chunk):
    """t_F / prefactor of the friction (regime 0) and limit (1) cases, tier by tier [-] (creeps: left 0)."""
    acc = xp.zeros(c["sm"].shape)
    rules = {0: _gauss(xp, _kernels.N_NODES), 1: _gauss(xp, _kernels.N_NODES_MASS)}
    x16, w16 = rules[0]
    for regime, panel in ((0, _friction_panel), (1, _limit_panel)):
        for tier in (0, 1, 2):
            idx = xp.nonzero((c["regime"] == regime) & (c["tier"] == tier))[0]
            if idx.size == 0:
                continue
            sub = _take(c, idx)
            if tier < 2:
                x, w = rules[tier]
                acc[idx] = panel(xp, x, w, 0.0, 1.0, sub)
                continue
            # the graded rule: a bounded number of node values at once (sub-chunks of the tier's cases)
            step = max(1, chunk // (2 * (_kernels.N_PANELS + 1)))
            for lo in range(0, int(idx.size), step):
                part = _take(sub, slice(lo, lo + step))
                jl = panel_counts(xp, xp.where(part["ratio"] > 0.0, xp.sqrt(xp.abs(part["ratio"])), 0.0))
                jr = panel_counts(xp, 0.5 * xp.sqrt(part["msq"]))
                total = xp.zeros(part["sm"].shape)
                for pidx, start, width in _graded_panels(xp, jl, jr):
                    total[pidx] += panel(xp, x16, w16, start, width, _take(part, pidx))
                acc[idx[lo:lo + step]] = total
    return acc


def stop_arrays(xp, E, alpha0, F1, F2, k, m2, L1, chunk: int = CHUNK):
    """(t_F [s], alpha_F [rad], code) of flat float64 ``xp`` arrays of valid releases (those of
    ``batch._stop_arrays``: screened by ``batch._screen``); code 0 friction, 1 geometric limit, 2 creeps (t_F = inf)."""
    return _stop_parts(xp, E, alpha0, F1, F2, k, m2, L1, chunk)[:3]


def _stop_parts(xp, E, alpha0, F1, F2, k, m2, L1, chunk):
    n = E.size
    t = xp.empty(n)
    aF = xp.empty(n)
    delta = xp.empty(n)
    code = xp.empty(n, dtype=xp.int8)
    for lo in range(0, n, chunk):
        sl = slice(lo, min(n, lo + chunk))
        c = _setup(xp, E[sl], alpha0[sl], F1[sl], F2[sl], k[sl], m2[sl], L1[sl])
        with np.errstate(all="ignore"):
            acc = _quadrature(xp, c, chunk)
            t[sl] = xp.where(c["regime"] == 2, xp.inf, c["pref"] * acc)
        aF[sl] = c["aF"]
        delta[sl] = c["delta"]
        code[sl] = c["regime"].astype(xp.int8)
    return t, aF, code, delta


# -- release envelope ----------------------------------------------------------------------------------------------

def _peak_head_velocity(xp, E, a0, aE, A, B, k, m2, n_samples: int = 8, newton: int = 5):
    """Peak of u_dot = sqrt(sin^2(a) K(a) / (m2 (k + sin^2 a))) over [alpha0, alpha_end] [m/s]: samples, then
    Newton's method on d ln(g)/d alpha from the best (``batch._peak_head_velocity`` calls this with numpy)."""
    frac = xp.arange(n_samples) / n_samples
    sa0, ca0 = xp.sin(a0), xp.cos(a0)

    def g(x, s, co, col):
        K = E[col] - A[col] * (s - sa0[col]) - B[col] * (ca0[col] - co)
        return s * s * xp.maximum(K, 0.0) / (k[col] + s * s), K

    col = (slice(None), None)
    a = a0[:, None] + (aE - a0)[:, None] * frac
    vals = g(a, xp.sin(a), xp.cos(a), col)[0]
    j = xp.argmax(vals, axis=1)
    rows = xp.arange(a.shape[0])
    best = vals[rows, j]
    x = a[rows, j]
    every = slice(None)
    for _ in range(newton):
        s, co = xp.sin(x), xp.cos(x)
        K = xp.maximum(g(x, s, co, every)[1], 1e-300)
        d = k + s * s
        Kp = -(A * co + B * s)
        Kpp = A * s - B * co
        with np.errstate(divide="ignore", invalid="ignore"):
            G = 2.0 * k * co / (s * d) + Kp / K
            Gp = 2.0 * k * (-d - 2.0 * s * s * co * co) / (s * s * d * d) + (Kpp / K - (Kp / K) ** 2)
            step = xp.where(Gp < 0, G / Gp, 0.0)
        step = xp.where(xp.isnan(step), 0.0, step)  # nan_to_num (an infinite step takes x to an end: clipped)
        x = xp.minimum(xp.maximum(x - step, a0), aE)
    s, co = xp.sin(x), xp.cos(x)
    best = xp.maximum(best, g(x, s, co, every)[0])
    return xp.sqrt(best / m2)


def _accel(xp, alpha, E, s0, c0, A, B, F1, F2, k, m2, L1, which):
    """u_ddot (which 0) or v_ddot (which 1) at alpha and its slope in alpha (``_kernels.head_hinge_acceleration``,
    vectorised: K < 0 taken as 0; the formula itself is ``_kernels.acceleration_terms``) [m/s^2], [m/s^2/rad]."""
    s = xp.sin(alpha)
    c = xp.cos(alpha)
    K = xp.maximum(E - A * (s - s0) - B * (c0 - c), 0.0)
    return _kernels.acceleration_terms(s, c, K, -A * c - B * s, F1, F2, k, m2, L1, which)


def _refine_peak(xp, lo, hi, args, which, max_iter: int = 200):
    """``_kernels.refine_peak`` vectorised: the maximum of |u_ddot| or |v_ddot| in [lo, hi] at the root of its
    slope (Illinois false position, to a bracket of 4 ulps or a zero slope) where the slope goes from + to -;
    -1 elsewhere [m/s^2]. Each step carries on only the cases not yet converged (their values gathered)."""
    g_lo, p_lo = _accel(xp, lo, *args, which)
    g_hi, p_hi = _accel(xp, hi, *args, which)
    f_lo = xp.where(g_lo >= 0.0, p_lo, -p_lo)
    f_hi = xp.where(g_hi >= 0.0, p_hi, -p_hi)
    valid = (f_lo > 0.0) & (f_hi < 0.0)
    x = 0.5 * (lo + hi)
    idx = xp.nonzero(valid)[0]
    lo, hi, f_lo, f_hi = lo[idx], hi[idx], f_lo[idx], f_hi[idx]
    sub = [a[idx] for a in args]
    side = xp.zeros(lo.shape, dtype=xp.int8)
    for _ in range(max_iter):
        if idx.size == 0:
            break
        with np.errstate(all="ignore"):
            xn = hi - f_hi * ((hi - lo) / (f_hi - f_lo))
        xn = xp.where((lo < xn) & (xn < hi), xn, 0.5 * (lo + hi))
        x[idx] = xn
        g, p = _accel(xp, xn, *sub, which)
        f = xp.where(g >= 0.0, p, -p)
        zero = f == 0.0
        pos = f > 0.0
        neg = ~zero & ~pos  # (a NaN slope counts as negative, as in the scalar loop)
        f_hi = xp.where(pos & (side == 1), 0.5 * f_hi, f_hi)
        f_lo = xp.where(neg & (side == -1), 0.5 * f_lo, f_lo)
        lo = xp.where(pos, xn, lo)
        f_lo = xp.where(pos, f, f_lo)
        hi = xp.where(neg, xn, hi)
        f_hi = xp.where(neg, f, f_hi)
        side = xp.where(pos, 1, xp.where(neg, -1, side)).astype(xp.int8)
        tight = (hi - lo) <= 8.8e-16 * xp.maximum(xp.abs(lo), xp.abs(hi))
        go = xp.nonzero(~zero & ~tight)[0]
        idx, lo, hi, f_lo, f_hi, side = idx[go], lo[go], hi[go], f_lo[go], f_hi[go], side[go]
        sub = [a[go] for a in sub]
    return xp.where(valid, xp.abs(_accel(xp, x, *args, which)[0]), -1.0)


def _peak_accelerations(xp, E, a0, aE, F1, F2, k, m2, L1, n: int = 65):
    """Peaks of |u_ddot| and |v_ddot| over [alpha0, alpha_end] (``_fast.peak_accel_kernel`` vectorised): n equally
    spaced angles by rotation pick the best sample (the first of equals), then the maximum at a root of the jerk
    bracketed by it and a neighbour [m/s^2]."""
    h = (aE - a0) / (n - 1)
    ch, sh = xp.cos(h), xp.sin(h)
    s0, c0 = xp.sin(a0), xp.cos(a0)
    s, c = s0, c0
    A = 2.0 * F1 * L1
    B = 4.0 * F2 * L1
    ml = m2 * L1
    best = [xp.full(E.shape, -1.0), xp.full(E.shape, -1.0)]
    at = [xp.zeros(E.shape, dtype=xp.int64), xp.zeros(E.shape, dtype=xp.int64)]
    for j in range(n):
        K = E - A * (s - s0) - B * (c0 - c)
        d = k + s * s
        rate2 = xp.maximum(K, 0.0) / (ml * L1 * d)
        acc = -rate2 * s * c / d - (2.0 * F2 * s + F1 * c) / (ml * d)
        for which, value in enumerate((L1 * (c * rate2 + s * acc), L1 * (-s * rate2 + c * acc))):
            mag = xp.abs(value)
            better = mag > best[which]
            best[which] = xp.where(better, mag, best[which])
            at[which] = xp.where(better, j, at[which])
        s, c = s * ch + c * sh, c * ch - s * sh
    args = (E, s0, c0, A, B, F1, F2, k, m2, L1)
    out = []
    for which in (0, 1):
        j = at[which].astype(xp.float64)
        peak = best[which]
        left = _refine_peak(xp, a0 + (j - 1.0) * h, a0 + j * h, args, which)
        right = _refine_peak(xp, a0 + j * h, a0 + (j + 1.0) * h, args, which)
        peak = xp.where(j > 0, xp.maximum(peak, left), peak)
        peak = xp.where(j < n - 1, xp.maximum(peak, right), peak)
        out.append(peak)
    return out


def release_arrays(xp, E, alpha0, F1, F2, k, m2, L1, chunk: int = CHUNK) -> dict:
    """The release envelope of ``batch.release`` from flat screened ``xp`` arrays: dict of stop_time, alpha_final,
    stopped_by, u_final, v_final, alpha_dot0, peak_u_dot, peak_v_dot, peak_u_ddot, peak_v_ddot (SI; Table 4,
    Eq. 6; the peaks as :func:`_peak_head_velocity` and :func:`_peak_accelerations`)."""
    t, aF, code, delta = _stop_parts(xp, E, alpha0, F1, F2, k, m2, L1, chunk)
    out = {"stop_time": t, "alpha_final": aF, "stopped_by": code}
    names = ("u_final", "v_final", "alpha_dot0", "peak_u_dot", "peak_v_dot", "peak_u_ddot", "peak_v_ddot")
    for name in names:
        out[name] = xp.empty(E.size)
    # the peak accelerations hold ~30 arrays of the chunk: a smaller chunk keeps memory bounded
    step = max(1, chunk // 4)
    with np.errstate(all="ignore"):
        for lo in range(0, E.size, step):
            sl = slice(lo, min(E.size, lo + step))
            a0, d = alpha0[sl], delta[sl]
            half_sum = a0 + 0.5 * d
            sigma_m = xp.sin(0.5 * d)
            out["u_final"][sl] = 2.0 * L1[sl] * xp.sin(half_sum) * sigma_m  # Table 4, cancellation-free
            out["v_final"][sl] = 2.0 * L1[sl] * xp.sin(dynamics.limit_sweep(a0) - 0.5 * d) * sigma_m
            sa0 = xp.sin(a0)
            ad0 = xp.sqrt(E[sl] / (m2[sl] * L1[sl] ** 2 * (k[sl] + sa0 * sa0)))  # Eq. 6
            out["alpha_dot0"][sl] = ad0
            out["peak_v_dot"][sl] = L1[sl] * xp.cos(a0) * ad0
            out["peak_u_dot"][sl] = _peak_head_velocity(xp, E[sl], a0, aF[sl], 2.0 * F1[sl] * L1[sl],
                                                        4.0 * F2[sl] * L1[sl], k[sl], m2[sl])
            pu, pv = _peak_accelerations(xp, E[sl], a0, aF[sl], F1[sl], F2[sl], k[sl], m2[sl], L1[sl])
            out["peak_u_ddot"][sl] = pu
            out["peak_v_ddot"][sl] = pv
    return out


# -- identification ------------------------------------------------------------------------------------------------

def _line_nodes(xp, x, w, start, width, c):
    """Node values of the identification (``_fast._line_nodes``) on one panel per case: P = w sqrt(k + sin^2 alpha)
    / q, b the remaining energy of pure rail friction over E_S w^2 and d = a - b (a: pure hinge friction) [-]."""
    u = start + width * x[:, None]
    sg = (u * u) * c["sm"]
    q = xp.sqrt(1.0 - sg * sg)
    sal = c["sA"] * (1.0 - 2.0 * sg * sg) - c["cA"] * 2.0 * sg * q
    P = (w[:, None] * width) * xp.sqrt(c["k"] + sal * sal) / q
    a = (c["cA"] * q + c["sA"] * sg) / c["c1"]
    b = (c["sA"] * q - c["cA"] * sg) / c["c2"]
    return P, a, b


def _graded_counts(xp, c):
    """(jl, jr): the graded panels of each case towards w = 0 and towards w = 1 (``_fast._graded_sum``) [-]."""
    jl = panel_counts(xp, xp.where(c["ratio"] > 0.0, xp.sqrt(xp.abs(c["ratio"])), 0.0))
    return jl, panel_counts(xp, 0.5 * xp.sqrt(c["msq"]))


def _line_arrays(xp, c, tier):
    """(P, a, b) node arrays (n_nodes x cases) of one tier. The graded tier's panels are laid out case by case in
    the order ``_fast._identify_one`` sums them (slot s: panel s towards w = 0 while s <= jl, then panel s - jl - 1
    towards w = 1), as many slots as the case with the most panels needs; a case's unused slots have P = 0, a = b = 1
    (they add nothing). The caller groups the cases by their panel count, so that few slots are unused [-]."""
    if tier < 2:
        x, w = _gauss(xp, _kernels.N_NODES if tier == 0 else _kernels.N_NODES_MASS)
        return _line_nodes(xp, x, w, 0.0, 1.0, c)
    x, w = _gauss(xp, _kernels.N_NODES)
    jl, jr = _graded_counts(xp, c)
    npan = jl + jr + 2
    his = xp.asarray(_panel_edges())
    rows = []
    for slot in range(int(xp.max(npan))):
        left = slot <= jl
        j = xp.minimum(xp.where(left, slot, slot - jl - 1), _kernels.N_PANELS)
        hi = his[j]
        last = xp.where(left, j == jl, j == jr)
        lo = xp.where(last, 0.0, hi * _kernels.GRADING)
        P, a, b = _line_nodes(xp, x, w, xp.where(left, lo, 1.0 - hi), hi - lo, c)
        used = slot < npan
        rows.append((xp.where(used, P, 0.0), xp.where(used, a, 1.0), xp.where(used, b, 1.0)))
    return tuple(xp.concatenate([r[i] for r in rows]) for i in range(3))


def _halley(xp, P, d, b, pref, tF, lam, active, tol, max_iter):
    """Halley's method in lambda (Newton's step where Halley's denominator is not > 1/2), as ``_fast._identify_one``:
    (lambda, iterations) [-]. Only the ``active`` cases iterate, and each step carries on only the cases not yet
    converged (their columns gathered: most converge in 3 steps, a few take up to ~16)."""
    lam_out = lam.copy()
    iters_out = xp.zeros(lam.shape, dtype=xp.int16)
    idx = xp.nonzero(active)[0]
    P, d, b, pref, tF, lam = P[:, idx], d[:, idx], b[:, idx], pref[idx], tF[idx], lam[idx]
    for step_no in range(1, max_iter + 1):
        if idx.size == 0:
            break
        h = b + lam * d
        r = 1.0 / xp.sqrt(h)
        pr = P * r
        e = d / h
        t0 = pr.sum(axis=0)
        pe = pr * e
        t1 = pe.sum(axis=0)
        t2 = (pe * e).sum(axis=0)
        with np.errstate(all="ignore"):
            f = pref * t0 - tF
            slope = -0.5 * pref * t1
            curve = 0.75 * pref * t2
            newton = f / slope
            denom = 1.0 - 0.5 * newton * curve / slope
            step = xp.where(denom > 0.5, newton / denom, newton)
            new = xp.minimum(xp.maximum(lam - step, 0.0), 1.0)
            done = xp.abs(new - lam) <= xp.maximum(tol, 8.0 * EPS * pref * t0 / xp.abs(slope))
        lam = new
        lam_out[idx] = lam
        iters_out[idx] = step_no
        go = xp.nonzero(~done)[0]
        idx, P, d, b, pref, tF, lam = idx[go], P[:, go], d[:, go], b[:, go], pref[go], tF[go], lam[go]
    return lam_out, iters_out


def identify_arrays(xp, alpha0, alpha_final, stop_time, E, k, m2, L1, tol: float = 1e-14, max_iter: int = 40,
                    chunk: int = CHUNK) -> dict:
    """``batch.identify`` of valid observations (alpha0 in (0, pi/2), alpha_F in (alpha0, pi/2), E_S, t_F, k, m2,
    L1 > 0; flat ``xp`` arrays): dict of lam (F1/F1*), F1_max, F2_max (Eq. 11-12) [N], stop_time_min,
    stop_time_max [s], status (0, 1, 2 of ``batch.IDENTIFY_STATUS``) and iterations, as ``_fast._identify_one``."""
    n = alpha0.size
    out = {name: xp.empty(n) for name in ("lam", "F1_max", "F2_max", "stop_time_min", "stop_time_max")}
    out["status"] = xp.zeros(n, dtype=xp.int8)
    out["iterations"] = xp.zeros(n, dtype=xp.int16)
    for lo in range(0, n, chunk):
        sl = slice(lo, min(n, lo + chunk))
        part = _identify_chunk(xp, alpha0[sl], alpha_final[sl], stop_time[sl], E[sl], k[sl], m2[sl], L1[sl], tol,
                               max_iter, chunk)
        for name, v in part.items():
            out[name][sl] = v
    return out


def _identify_chunk(xp, a0, aF, tF, E, k, m2, L1, tol, max_iter, chunk):
    with np.errstate(all="ignore"):  # the setup of every back-end (Eq. 11-13), elementwise on xp's arrays
        sA, cA, sm, c1, c2, F1max, F2max, ratio, msq, pref = _identify_setup.for_arrays(xp)(a0, aF, E, k, m2, L1)
    c = {"sm": sm, "sA": sA, "cA": cA, "c1": c1, "c2": c2, "k": k, "ratio": ratio, "msq": msq, "pref": pref,
         "tF": tF, "a0": a0, "aF": aF}
    tier = _tier(xp, ratio, msq)
    n = a0.size
    lam = xp.full(n, xp.nan)
    t_lo = xp.empty(n)
    t_hi = xp.empty(n)
    status = xp.zeros(n, dtype=xp.int8)
    iters = xp.zeros(n, dtype=xp.int16)
    groups = [(0, xp.nonzero(tier == 0)[0], chunk), (1, xp.nonzero(tier == 1)[0], chunk)]
    graded = xp.nonzero(tier == 2)[0]
    if graded.size:  # the graded tier by panel count (few unused slots), in sub-chunks of ~24 chunk node values
        jl, jr = _graded_counts(xp, _take(c, graded))
        npan = jl + jr + 2
        for count in to_host(xp.unique(npan)):
            groups.append((2, graded[npan == count], max(1, (chunk * _kernels.N_NODES_MASS)
                                                       // (_kernels.N_NODES * int(count)))))
    for tr, idx, step in groups:
        for start in range(0, int(idx.size), step):
            sub_idx = idx[start:start + step]
            sub = _take(c, sub_idx)
            lm, lo, hi, st, it = _identify_tier(xp, sub, tr, tol, max_iter)
            lam[sub_idx], t_lo[sub_idx], t_hi[sub_idx], status[sub_idx], iters[sub_idx] = lm, lo, hi, st, it
    return {"lam": lam, "F1_max": F1max, "F2_max": F2max, "stop_time_min": t_lo, "stop_time_max": t_hi,
            "status": status, "iterations": iters}


def _identify_tier(xp, c, tier, tol, max_iter):
    P, a, b = _line_arrays(xp, c, tier)
    d = a - b
    with np.errstate(all="ignore"):
        lo = c["pref"] * (P / xp.sqrt(b)).sum(axis=0)
        hi = c["pref"] * (P / xp.sqrt(a)).sum(axis=0)
        tF, a0, aF = c["tF"], c["a0"], c["aF"]
        # an observation within rounding of an end of the feasible interval is that end (F1 = 0 or F2 = 0)
        at_lo = xp.abs(tF - lo) <= _kernels.feasible_slack(lo, a0, aF, 0.0)
        at_hi = ~at_lo & ((xp.abs(tF - hi) <= _kernels.feasible_slack(hi, a0, aF, 0.0))
                          | ((hi < tF) & (tF <= hi + _kernels.feasible_slack(hi, a0, aF, 1.0))))
        below = ~at_lo & ~at_hi & (tF < lo)
        above = ~at_lo & ~at_hi & ~below & (tF > hi)
        inside = ~(at_lo | at_hi | below | above)
        start = xp.minimum(xp.maximum(((lo / tF) ** 2 - 1.0) / ((lo / hi) ** 2 - 1.0), 0.0), 1.0)
        start = xp.where(inside, start, 0.0)
    lam, iters = _halley(xp, P, d, b, c["pref"], tF, start, inside, tol, max_iter)
    lam = xp.where(at_lo, 0.0, xp.where(at_hi, 1.0, xp.where(below | above, xp.nan, lam)))
    status = xp.where(below, 1, xp.where(above, 2, 0)).astype(xp.int8)
    return lam, lo, hi, status, iters
