"""Compiled (numba) loops of the batch kernels: the formulas of :mod:`quickrelease.device._kernels`, fused.

numpy evaluates ``_kernels`` one operation at a time, about 17 passes over the (nodes x cases) arrays; here the
stop time goes in blocks of :data:`STOP_BLOCK` cases: the library calls of the setup one case at a time (sin and
cos of alpha0: libm's, which numpy calls too, so the same bits), the rest of the setup (the classifier and Eq. 8,
plain IEEE arithmetic, no fastmath) for both regimes at once and selected without a branch, which the compiler
vectorises across the cases (:func:`_setup_vector`), then each case's node sums, vectorised across its nodes
(``fastmath`` reassociation only). Every function here has numpy's error model (a division by zero gives inf or
NaN, as numpy's does, and never raises). The formulas, node rules and tier criteria are those of ``_kernels`` (a
test checks the two agree case by case), every tier compiled: the graded one with only the panels a case needs
(:func:`_graded_sum`). The identification runs over numba's threads (``prange`` over blocks of :data:`BLOCK` cases),
the stop time over a thread pool of chunks (``batch._stop_arrays``); each case is computed alone, so the results are
bit-identical on any number of threads. Compiled on first use and cached on disk (``cache=True``).
"""

from __future__ import annotations

import hashlib
import math
import os
import types

import numpy as np
from llvmlite import ir as _ir
from numba import njit, prange
from numba import types as _nbtypes
from numba.core import cgutils
from numba.extending import intrinsic

from ..device import _kernels, dynamics
from . import _identify_setup

_HALF_PI = 0.5 * math.pi
#: Grading steps past a near-singularity's distance that the graded rule goes on panelling (calibrated against
#: the full 544-node rule of ``_kernels.graded_unit`` and mpmath: tests/test_kernels_wide.py).
GRADED_REACH = 1


#: The modules whose functions the kernels of this file compile in (inline): their sources stamp the cache.
_DEPENDENCIES = (dynamics, _kernels, _identify_setup)
_STAMP_FILE = "_fast.dependencies.sha256"


def _dependency_stamp() -> str:
    """sha256 of the sources of :data:`_DEPENDENCIES` (what the cached kernels of this file were compiled from)."""
    digest = hashlib.sha256()
    for module in _DEPENDENCIES:
        with open(module.__file__, "rb") as f:
            digest.update(f.read())
    return digest.hexdigest()


def _refresh_stale_cache(kernels, stamp: str | None = None) -> bool:
    """Drop the cached kernels of this file when the modules they inline have changed; True when it did.

    numba stamps a cached function with its own source file only (its mtime and size in older releases, a
    sha256 of its content since 0.6x), and the kernels here inline functions of
    :mod:`quickrelease.device.dynamics`, :mod:`quickrelease.device._kernels` and
    :mod:`quickrelease.batch._identify_setup`: after an edit or a checkout that changes
    those alone, the cached kernels would keep the old formulas (a stale kernel once made batch and simulate differ
    by an ulp, and another reported a release as creeping that the numpy path stopped by friction; without the
    setup's file in the stamp, a planted error in it left the compiled identification passing its tests while the
    numpy and GPU back-ends failed them). So the sha256 of those sources is kept beside
    the cache; where it differs (or is missing) the kernels' cache indexes are flushed and they recompile on first
    use. (Touching this file, the earlier remedy, invalidates nothing once numba hashes the content.) A read-only
    install is left as is.
    """
    try:
        stamp = stamp or _dependency_stamp()
        path = os.path.join(kernels[0]._cache.cache_path, _STAMP_FILE)
        try:
            with open(path) as f:
                if f.read() == stamp:
                    return False
        except FileNotFoundError:
            pass
        for kernel in kernels:
            kernel._cache.flush()
        with open(path, "w") as f:
            f.write(stamp)
        return True
    except (OSError, AttributeError):
        return False


def rules() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The 16- and 24-node Gauss-Legendre rules on [0, 1] (as in ``_kernels``)."""
    x16, w16 = _kernels.gauss_unit(_kernels.N_NODES)
    x24, w24 = _kernels.gauss_unit(_kernels.N_NODES_MASS)
    return x16, w16, x24, w24


def _jit(fn, **calls):
    """``fn`` compiled as written (cached, nogil, numpy's error model: a division by zero gives inf or NaN as numpy's
    does, never an exception), the module-level functions it calls bound to compiled ones."""
    if calls:
        fn = types.FunctionType(fn.__code__, {**fn.__globals__, **calls}, fn.__name__, fn.__defaults__)
    return njit(cache=True, nogil=True, error_model="numpy")(fn)


#: The classifier of the stop and the cancellation-free sweep of Eq. 8, compiled from the very functions
#: the numpy path calls (:mod:`quickrelease.device.dynamics`): one definition, the same rounding.
_one_minus_sin = _jit(dynamics.one_minus_sin_terms)
_limit_margin = _jit(dynamics.limit_margin_terms, _limit_dissipation=_jit(
    dynamics._limit_dissipation, one_minus_sin_terms=_one_minus_sin))
_limit_sweep = _jit(dynamics.limit_sweep)
_creeps = _jit(dynamics.creeps_terms)
_stop_terms = _jit(dynamics._stop_terms, limit_margin_terms=_limit_margin)
_sweep_sides = _jit(dynamics.sweep_sides)
_amplitude = _jit(dynamics.amplitude_terms)
_slack = njit(cache=True, nogil=True, error_model="numpy")(_kernels.feasible_slack)


@njit(cache=True, nogil=True, error_model="numpy")
def _tier(ratio, msq, near, hard, mass_sq, mass_hard_sq):
    """The rule of a case, as ``_kernels.tier_of``: 2 graded (left to numpy), 1 the 24-node rule, 0 16 nodes."""
    if ratio < hard or msq < mass_hard_sq:
        return 2
    if ratio < near or msq < mass_sq:
        return 1
    return 0


def tier_constants() -> tuple[float, float, float, float]:
    """(NEAR_RATIO, HARD_RATIO, MASS_RATIO^2, MASS_HARD^2) of ``_kernels``, in the kernels' argument order."""
    return _kernels.NEAR_RATIO, _kernels.HARD_RATIO, _kernels.MASS_RATIO**2, _kernels.MASS_HARD**2


#: Cases per block of the parallel loops (``prange`` over blocks): each case's arithmetic is its own, so the
#: results do not depend on how the blocks are shared among the threads (a test checks 1 and 2 threads agree
#: bit for bit).
BLOCK = 256
#: fastmath only where it is harmless and pays: the node sums (reassociated, so the compiler vectorises them; with
#: numpy's error model, so that a division is not a branch), never the classifier or the near-limit arithmetic of
#: the setup. Not "contract": with it, a kernel freshly compiled and the same kernel loaded from numba's cache
#: fused different multiply-adds (46k of 400k results a few ulps apart), so a Dask worker or a resumed run (cache)
#: disagreed with the process that compiled them; tests/test_kernels_wide.py checks fresh against cached.
_NODE_MATH = {"reassoc"}


@njit(cache=True, nogil=True, fastmath=_NODE_MATH, error_model="numpy")
def _friction_nodes(x, w, lo, width, sm, sA, cA, cb, sn, kk):
    """sum_j w_j sqrt((k + sin^2 alpha) / (C q^2)) over the nodes lo + width x_j of one panel, times width (the
    friction integrand of ``_kernels``: sigma = sigma_m u^2, C = cos(a - phi) q + sin(a - phi) sigma) [-]."""
    acc = 0.0
    for j in range(x.size):
        u = lo + width * x[j]
        sg = (u * u) * sm
        s2 = sg * sg
        q2 = 1.0 - s2
        q = math.sqrt(q2)
        sal = sA * (1.0 - 2.0 * s2) - cA * 2.0 * sg * q
        C = cb * q + sn * sg
        acc += w[j] * math.sqrt((kk + sal * sal) / (C * q2))
    return acc * width


@njit(cache=True, nogil=True, fastmath=_NODE_MATH, error_model="numpy")
def _limit_nodes(x, w, lo, width, sm, Kl, A, B, kk):
    """sum_j w_j u_j sqrt(k + sin^2 alpha) / sqrt(K q^2) over the nodes u_j = lo + width x_j of one panel, times
    width (the geometric-limit integrand of ``_kernels``: K = K_lim + 2 A sigma^2 + 2 B sigma q) [-]."""
    acc = 0.0
    for j in range(x.size):
        u = lo + width * x[j]
        s = (u * u) * sm
        s2 = s * s
        q2 = 1.0 - s2
        sal = 1.0 - 2.0 * s2
        K = Kl + 2.0 * A * s2 + 2.0 * B * s * math.sqrt(q2)
        acc += w[j] * u * math.sqrt(kk + sal * sal) / math.sqrt(K * q2)
    return acc * width


@njit(cache=True, nogil=True, error_model="numpy")
def _panel_count(distance, grading, reach, panels):
    """Graded panels towards an end whose near-singularity lies ``distance`` from it (in w): the last panel
    [0, r^J / 2] ends ``reach`` grading steps inside that distance, J in [0, panels] [-]."""
    if not distance > 0.0:
        return panels
    j = math.ceil(math.log(2.0 * distance) / math.log(grading)) + reach
    return min(max(j, 0), panels)


@njit(cache=True, nogil=True, error_model="numpy")
def _panel_sum(regime, x, w, lo, width, sm, sA, cA, cb, sn, Kl, A, B, kk):
    if regime == 0:
        return _friction_nodes(x, w, lo, width, sm, sA, cA, cb, sn, kk)
    return _limit_nodes(x, w, lo, width, sm, Kl, A, B, kk)


@njit(cache=True, nogil=True, error_model="numpy")
def _graded_sum(regime, ratio, msq, x, w, grading, reach, panels, sm, sA, cA, cb, sn, Kl, A, B, kk):
    """The graded rule of ``_kernels.graded_unit`` with only the panels a case needs: towards w = 0 down to
    ``sqrt(ratio)`` (the end's near-singularity), towards w = 1 down to ``sqrt(msq) / 2`` (the mass factor's
    complex zero), each ``reach`` steps further; the rest of each half is one panel [-]."""
    jl = _panel_count(math.sqrt(ratio) if ratio > 0.0 else 0.0, grading, reach, panels)
    jr = _panel_count(0.5 * math.sqrt(msq), grading, reach, panels)
    acc = 0.0
    hi = 0.5
    for _ in range(jl):  # [r^(j+1)/2, r^j/2] towards 0
        lo = hi * grading
        acc += _panel_sum(regime, x, w, lo, hi - lo, sm, sA, cA, cb, sn, Kl, A, B, kk)
        hi = lo
    acc += _panel_sum(regime, x, w, 0.0, hi, sm, sA, cA, cb, sn, Kl, A, B, kk)
    hi = 0.5
    for _ in range(jr):  # mirrored towards 1
        lo = hi * grading
        acc += _panel_sum(regime, x, w, 1.0 - hi, hi - lo, sm, sA, cA, cb, sn, Kl, A, B, kk)
        hi = lo
    acc += _panel_sum(regime, x, w, 1.0 - hi, hi, sm, sA, cA, cb, sn, Kl, A, B, kk)
    return acc


@njit(cache=True, nogil=True, error_model="numpy")
def _stop_one(E, sa0, ca0, a0, F1, F2, kk, m2, L1, x16, w16, x24, w24, near, hard, mass_sq, mass_hard_sq,
              grading, reach, panels):
    """(t_F, alpha_F, regime code, tier, N, D) of one release (0 friction, 1 limit, 2 creeps: t_F = inf).

    A friction stop's sweep is ``delta = atan2(N, D)`` (Eq. 8, :func:`dynamics.sweep_sides`); nothing here needs
    delta itself but alpha_F (the quadrature takes sin(delta / 2) from N and D, the tier the chord 2 sin(delta / 2)),
    so alpha_F is left NaN for friction stops, for the caller to take as numpy's
    ``min(alpha0 + max(atan2(N, D), 0), pi/2)``: the angle of the single-case solver to the last bit, and one
    vectorised call instead of one scalar atan2 a case (a third of the setup). Whether the stop is at pi/2 within
    rounding (``delta >= pi/2 - alpha0``, as numpy decides it) is read from the sign of
    ``N sin(alpha0) - D cos(alpha0) ~ sin(delta - (pi/2 - alpha0))`` away from 0, from atan2 itself near 0."""
    A = 2.0 * F1 * L1
    B = 4.0 * F2 * L1
    R = _amplitude(A, B)
    Kl = _limit_margin(E, A, B, sa0, ca0)
    N = 0.0
    D = 1.0
    if _creeps(Kl, E, A, B):  # creeps towards pi/2 and never arrives (dynamics.creeps_terms)
        return math.inf, _HALF_PI, 2, 0, N, D
    to_limit = _limit_sweep(a0)  # pi/2 - alpha0, two-term pi/2
    if Kl > 0.0:  # the rhombus becomes flat first: anchor pi/2
        regime = 1
        sm = math.sin(0.5 * to_limit)
        qm = math.sqrt(1.0 - sm * sm)
        ratio = Kl / (Kl + 2.0 * A * sm * sm + 2.0 * B * sm * qm)
        aF = _HALF_PI
        sA = 1.0
        cA = 0.0
        cb = 0.0
        s = 1.0
        pref = 4.0 * sm * L1 * math.sqrt(m2)
    else:  # friction stop at alpha_F (Eq. 8)
        regime = 0
        # the terms of dynamics.sweep_terms once: delta = atan2(N, D), cb = cos(alpha_F - phi), s = u (as numpy)
        s0, cv, e, s, cb = _stop_terms(E, A, B, R, sa0, ca0)
        N, D = _sweep_sides(s0, cv, e, s, cb)
        g = N * sa0 - D * ca0
        flat = math.atan2(N, D) >= to_limit if abs(g) <= 1e-9 else g > 0.0
        if flat:
            # a friction stop at pi/2 within rounding: sin, cos of alpha_F - phi there, as numpy does
            s = A / R
            cb = B / R
            sm = math.sin(0.5 * to_limit)
            aF = min(a0 + to_limit, _HALF_PI)
        else:
            # sin(delta / 2) from (N, D) = r (sin delta, cos delta), D >= 0: N / sqrt(2 r (r + D)), no call
            r = math.sqrt(N * N + D * D)  # ~1: N, D are a sine and a cosine up to rounding
            sm = N / math.sqrt(2.0 * r * (r + D)) if N > 0.0 else 0.0
            aF = math.nan
        sA = (B * cb + A * s) / R
        cA = (A * cb - B * s) / R
        qm = math.sqrt(1.0 - sm * sm)
        ratio = cb / (cb * qm + s * sm)
        pref = 4.0 * L1 * math.sqrt(sm) * math.sqrt(m2) / math.sqrt(2.0 * R)
    msq = (kk + sa0 * sa0) / (4.0 * sm * sm) if sm > 0.0 else math.inf  # over the chord (_kernels.tier_of)
    tier = _tier(ratio, msq, near, hard, mass_sq, mass_hard_sq)
    if tier == 2:
        acc = _graded_sum(regime, ratio, msq, x16, w16, grading, reach, panels, sm, sA, cA, cb, s, Kl, A, B, kk)
    elif tier == 1:
        acc = _panel_sum(regime, x24, w24, 0.0, 1.0, sm, sA, cA, cb, s, Kl, A, B, kk)
    else:
        acc = _panel_sum(regime, x16, w16, 0.0, 1.0, sm, sA, cA, cb, s, Kl, A, B, kk)
    return pref * acc, aF, regime, tier, N, D


@intrinsic
def _sqrt(typingctx, x):
    """The square root as LLVM's ``llvm.sqrt`` intrinsic: correctly rounded, as libm's ``sqrt`` (which numba's
    ``math.sqrt`` calls), but known to the compiler as free of side effects, so that a loop containing it can be
    vectorised across cases (the call cannot)."""
    if x is not _nbtypes.float64:
        return None

    def codegen(context, builder, signature, args):
        fn = builder.module.declare_intrinsic("llvm.sqrt", [_ir.DoubleType()])
        return builder.call(fn, args)

    return _nbtypes.float64(_nbtypes.float64), codegen


def _libm(name):
    """libm's ``name`` (a double -> double function) called as an opaque function (``nobuiltin``): never replaced by
    the compiler, never vectorised. numba's ``math.sin`` is LLVM's ``llvm.sin`` intrinsic, which a vectorised loop turns
    into the vector library's ``sin`` where numba has one (Intel's SVML), whose last bits differ from libm's; numpy's
    ``sin`` and ``cos`` are libm's, and the single-case solver takes sin and cos of alpha0 from them."""

    @intrinsic
    def call(typingctx, x):
        if x is not _nbtypes.float64:
            return None

        def codegen(context, builder, signature, args):
            double = _ir.DoubleType()
            fn = cgutils.get_or_insert_function(builder.module, _ir.FunctionType(double, [double]), name)
            fn.attributes.add("nobuiltin")
            return builder.call(fn, args)

        return _nbtypes.float64(_nbtypes.float64), codegen

    return call


_libm_sin = _libm("sin")


@intrinsic
def _libm_sincos(typingctx, x):
    """``(sin(x), cos(x))`` by libm's ``sincos``, called opaquely as :func:`_libm`'s functions are: one argument
    reduction for both (2.5 ns a case less than the two calls here); glibc's ``sincos`` gives the bits of its ``sin``
    and ``cos`` (a test checks against numpy's)."""
    if x is not _nbtypes.float64:
        return None
    tuple_type = _nbtypes.UniTuple(_nbtypes.float64, 2)

    def codegen(context, builder, signature, args):
        double = _ir.DoubleType()
        fnty = _ir.FunctionType(_ir.VoidType(), [double, double.as_pointer(), double.as_pointer()])
        fn = cgutils.get_or_insert_function(builder.module, fnty, "sincos")
        fn.attributes.add("nobuiltin")
        s = cgutils.alloca_once(builder, double)
        c = cgutils.alloca_once(builder, double)
        builder.call(fn, [args[0], s, c])
        return context.make_tuple(builder, tuple_type, [builder.load(s), builder.load(c)])

    return tuple_type(_nbtypes.float64), codegen


def _jit_vector(fn, **calls):
    """``fn`` compiled as :func:`_jit` does, with numpy's error model (a division by zero gives inf or NaN, not a
    branch that raises): for the branch-free loops that compute both sides of a choice and select one, which the
    compiler then vectorises across cases. The arithmetic (IEEE, no fastmath) rounds as ``_jit``'s does."""
    calls = {"np": _VECTOR_NP, **calls}
    fn = types.FunctionType(fn.__code__, {**fn.__globals__, **calls}, fn.__name__, fn.__defaults__)
    return njit(cache=True, nogil=True, error_model="numpy", inline="always")(fn)


#: ``np`` as the functions of :mod:`quickrelease.device.dynamics` compiled by :func:`_jit_vector` see it: numpy,
#: its square root the vectorisable :func:`_sqrt` (same rounding).
_VECTOR_NP = types.ModuleType("numpy_vector")
_VECTOR_NP.sqrt = _sqrt
_VECTOR_NP.maximum = np.maximum
_VECTOR_NP.abs = np.abs

_v_one_minus_sin = _jit_vector(dynamics.one_minus_sin_terms)
_v_limit_margin = _jit_vector(dynamics.limit_margin_terms, _limit_dissipation=_jit_vector(
    dynamics._limit_dissipation, one_minus_sin_terms=_v_one_minus_sin))
_v_creeps = _jit_vector(dynamics.creeps_terms)
_v_stop_terms = _jit_vector(dynamics._stop_terms, limit_margin_terms=_v_limit_margin)
_v_sweep_sides = _jit_vector(dynamics.sweep_sides)
_v_amplitude = _jit_vector(dynamics.amplitude_terms)


#: Cases per block of the stop-time kernel: its setup scratch (:data:`_ROWS` rows of this many values, one array) stays
#: in the first-level cache.
STOP_BLOCK = 128
#: Rows of the stop-time kernel's scratch: the block's inputs (copied in, with the libm results), then the setup's
#: outputs. One array, row r at ``r * STOP_BLOCK``: the compiler sees every access at a constant distance from the
#: others, so it vectorises the setup loop without runtime overlap checks (with one array per quantity it needed more
#: such checks than it allows, and left the loop scalar).
(_E, _A, _B, _L1, _KK, _M2, _SA0, _CA0, _KL, _SL, _N, _D, _SM, _SAL, _CAL, _CB, _SN, _PREF, _RATIO, _MSQ, _REG,
 _SCALAR) = range(22)
_ROWS = 22


@njit(cache=True, nogil=True, error_model="numpy")
def _setup_calls(E, a0, F1, F2, kk, m2, L1, lo, hi, W):
    """The library calls of the setup of cases lo..hi-1, one case at a time, into the scratch W: sin and cos of
    alpha0 (libm's, which numpy calls too: the same bits), the classifier's margin K_lim and, where it is > 0 (the
    geometric limit), ``sin((pi/2 - alpha0) / 2)``; with the inputs the vectorised part reads."""
    for i in range(lo, hi):
        j = i - lo
        s, c = _libm_sincos(a0[i])
        A = 2.0 * F1[i] * L1[i]
        B = 4.0 * F2[i] * L1[i]
        k = _limit_margin(E[i], A, B, s, c)
        W[_E * STOP_BLOCK + j] = E[i]
        W[_A * STOP_BLOCK + j] = A
        W[_B * STOP_BLOCK + j] = B
        W[_L1 * STOP_BLOCK + j] = L1[i]
        W[_KK * STOP_BLOCK + j] = kk[i]
        W[_M2 * STOP_BLOCK + j] = m2[i]
        W[_SA0 * STOP_BLOCK + j] = s
        W[_CA0 * STOP_BLOCK + j] = c
        W[_KL * STOP_BLOCK + j] = k
        W[_SL * STOP_BLOCK + j] = _libm_sin(0.5 * _limit_sweep(a0[i])) if k > 0.0 else 0.0


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _setup_vector(W, m):
    """The rest of the setup of :func:`_stop_one` for the first m cases of the scratch W, without a branch (both
    regimes computed, one selected), so that the compiler vectorises it across cases: the same operations on the
    same values as ``_stop_one``, so the same bits. Row ``_SCALAR`` marks (1.0) the cases left to ``_stop_one``
    whole: creeping ones and friction stops at pi/2 within rounding (both rare)."""
    for j in range(m):
        E = W[_E * STOP_BLOCK + j]
        A = W[_A * STOP_BLOCK + j]
        B = W[_B * STOP_BLOCK + j]
        L1 = W[_L1 * STOP_BLOCK + j]
        r_ = _v_amplitude(A, B)
        k_lim = W[_KL * STOP_BLOCK + j]
        s_a0 = W[_SA0 * STOP_BLOCK + j]
        c_a0 = W[_CA0 * STOP_BLOCK + j]
        lim = k_lim > 0.0
        s0, cv, e, s, c_b = _v_stop_terms(E, A, B, r_, s_a0, c_a0)
        n_, d_ = _v_sweep_sides(s0, cv, e, s, c_b)
        g = n_ * s_a0 - d_ * c_a0
        rr = _sqrt(n_ * n_ + d_ * d_)
        smf = n_ / _sqrt(2.0 * rr * (rr + d_))
        smf = smf if n_ > 0.0 else 0.0
        s_m = W[_SL * STOP_BLOCK + j] if lim else smf
        qm = _sqrt(1.0 - s_m * s_m)
        rf = c_b / (c_b * qm + s * s_m)
        rl = k_lim / (k_lim + 2.0 * A * s_m * s_m + 2.0 * B * s_m * qm)
        sq_m2 = _sqrt(W[_M2 * STOP_BLOCK + j])
        pf = 4.0 * L1 * _sqrt(s_m) * sq_m2 / _sqrt(2.0 * r_)
        pl = 4.0 * s_m * L1 * sq_m2
        W[_N * STOP_BLOCK + j] = 0.0 if lim else n_
        W[_D * STOP_BLOCK + j] = 1.0 if lim else d_
        W[_SM * STOP_BLOCK + j] = s_m
        W[_SAL * STOP_BLOCK + j] = 1.0 if lim else (B * c_b + A * s) / r_
        W[_CAL * STOP_BLOCK + j] = 0.0 if lim else (A * c_b - B * s) / r_
        W[_CB * STOP_BLOCK + j] = 0.0 if lim else c_b
        W[_SN * STOP_BLOCK + j] = 1.0 if lim else s
        W[_RATIO * STOP_BLOCK + j] = rl if lim else rf
        W[_PREF * STOP_BLOCK + j] = pl if lim else pf
        W[_MSQ * STOP_BLOCK + j] = ((W[_KK * STOP_BLOCK + j] + s_a0 * s_a0) / (4.0 * s_m * s_m) if s_m > 0.0
                                    else math.inf)
        W[_REG * STOP_BLOCK + j] = 1.0 if lim else 0.0
        creep = _v_creeps(k_lim, E, A, B)
        flat = (not lim) and (abs(g) <= 1e-9 or g > 0.0)
        W[_SCALAR * STOP_BLOCK + j] = 1.0 if (creep or flat) else 0.0


@njit(cache=True, nogil=True, error_model="numpy")
def stop_kernel_sides(E, a0, F1, F2, k, m2, L1, x16, w16, x24, w24, near, hard, mass_sq, mass_hard_sq,
                      t_out, aF_out, N_out, D_out, code_out):
    """t_F, alpha_F and the regime code (0 friction, 1 limit, 2 creeps to the limit: t_F = inf) of every case, every
    tier compiled (the graded one with the panels it needs: :func:`_graded_sum`); a friction stop's alpha_F is left
    NaN and its ``(N, D)`` written out (``delta = atan2(N, D)``; (0, 1) elsewhere) for the caller.

    In blocks of :data:`STOP_BLOCK` cases: the library calls of the setup (:func:`_setup_calls`: sin and cos of
    alpha0, to the bit those of numpy), the rest of the setup vectorised across the block (:func:`_setup_vector`),
    then each case's node sums (vectorised across its nodes), the fixed-rule cases listed by regime and rule first
    (so that the loop over each list has no branch that depends on the case); the rare cases the vectorised setup
    cannot settle (creeping, a friction stop at pi/2 within rounding) go through :func:`_stop_one` whole. The
    results are those of :func:`_stop_one` case by case, bit for bit (a test checks). One thread, without the GIL:
    ``batch._stop_arrays`` runs it on numba's thread count of chunks at once, each with its numpy post-processing
    (:func:`batch._stop_chunk`). numpy's error model: the setup computes both regimes of every case and selects one,
    so a division by zero in the regime not taken must give inf or NaN, not raise (and with the default model the
    compiler cannot vectorise the loops it inlines)."""
    n = E.size
    SB = STOP_BLOCK
    W = np.empty(_ROWS * SB)
    lists = np.empty(4 * SB, dtype=np.int64)
    count = np.zeros(4, dtype=np.int64)
    grading = _kernels.GRADING
    panels = _kernels.N_PANELS
    for lo in range(0, n, SB):
        hi = min(n, lo + SB)
        _setup_calls(E, a0, F1, F2, k, m2, L1, lo, hi, W)
        _setup_vector(W, hi - lo)
        count[:] = 0
        for i in range(lo, hi):
            j = i - lo
            reg = 1 if W[_REG * SB + j] != 0.0 else 0
            aF_out[i] = _HALF_PI if reg == 1 else math.nan
            N_out[i] = W[_N * SB + j]
            D_out[i] = W[_D * SB + j]
            code_out[i] = reg
            if W[_SCALAR * SB + j] != 0.0:
                t, aF, code, _, n_, d_ = _stop_one(E[i], W[_SA0 * SB + j], W[_CA0 * SB + j], a0[i], F1[i], F2[i],
                                                   k[i], m2[i], L1[i], x16, w16, x24, w24, near, hard, mass_sq,
                                                   mass_hard_sq, grading, GRADED_REACH, panels)
                t_out[i] = t
                aF_out[i] = aF
                N_out[i] = n_
                D_out[i] = d_
                code_out[i] = code
                continue
            ratio = W[_RATIO * SB + j]
            msq = W[_MSQ * SB + j]
            tier = _tier(ratio, msq, near, hard, mass_sq, mass_hard_sq)
            if tier == 2:
                t_out[i] = W[_PREF * SB + j] * _graded_sum(
                    reg, ratio, msq, x16, w16, grading, GRADED_REACH, panels, W[_SM * SB + j], W[_SAL * SB + j],
                    W[_CAL * SB + j], W[_CB * SB + j], W[_SN * SB + j], W[_KL * SB + j], W[_A * SB + j],
                    W[_B * SB + j], k[i])
                continue
            group = 2 * reg + tier  # the fixed rules, listed by regime and rule without a branch
            lists[group * SB + count[group]] = j
            count[group] += 1
        for group in range(4):  # each list with one regime and one rule: no branch per case
            reg = group // 2
            x = x24 if group % 2 else x16
            w = w24 if group % 2 else w16
            for c in range(count[group]):
                j = lists[group * SB + c]
                acc = _panel_sum(reg, x, w, 0.0, 1.0, W[_SM * SB + j], W[_SAL * SB + j], W[_CAL * SB + j],
                                 W[_CB * SB + j], W[_SN * SB + j], W[_KL * SB + j], W[_A * SB + j],
                                 W[_B * SB + j], k[lo + j])
                t_out[lo + j] = W[_PREF * SB + j] * acc


@njit(cache=True, nogil=True, error_model="numpy")
def screen_flags(E, F1, F2, L1, negligible, bad, tiny):
    """The cases batch cannot hand to the kernels as they are, in one pass; returns how many: ``bad`` where E_S is not
    positive and finite or ``A = 2 F1 L1``, ``B = 4 F2 L1`` overflow, ``tiny`` where the friction work to the flat
    rhombus, at most ``A + B``, is below ``negligible`` E_S (``batch._screen``: the same products, rounded alike)."""
    count = 0
    for i in range(E.size):
        A = 2.0 * F1[i] * L1[i]
        B = 4.0 * F2[i] * L1[i]
        b = not (math.isfinite(E[i]) and E[i] > 0.0 and math.isfinite(A) and math.isfinite(B))
        t = (not b) and A + B <= negligible * E[i]
        bad[i] = b
        tiny[i] = t
        if b or t:
            count += 1
    return count


@njit(cache=True, nogil=True, error_model="numpy")
def friction_angles(delta, a0, aF):
    """alpha_F = min(alpha0 + max(delta, 0), pi/2) where the stop-time kernel left alpha_F NaN (friction stops), from
    the sweep ``delta = atan2(N, D)`` that numpy computed (Eq. 8), in place: the arithmetic of the single-case
    solver's ``final_angle``, in one pass [rad]."""
    for i in range(aF.size):
        if math.isnan(aF[i]):
            aF[i] = min(a0[i] + max(delta[i], 0.0), _HALF_PI)


#: Nodes of the longest rule: the graded one with every panel (:func:`_graded_sum`).
MAX_NODES = 32 * (_kernels.N_PANELS + 1)


@njit(cache=True, nogil=True, fastmath=_NODE_MATH, error_model="numpy")
def _line_nodes(x, w, lo, width, sm, sA, cA, c1, c2, kk, P, d, b, off):
    """The node values of the identification on one panel (nodes lo + width x_j), written at ``off``:
    ``P = w sqrt(k + sin^2 alpha) / q``, ``b`` the remaining energy of pure rail friction and ``d = a - b`` (a that of
    pure hinge friction), both over E_S w^2, so that ``K = E_S w^2 (b + lambda d)``; returns
    (sum P / sqrt(b), sum P / sqrt(a)): the two ends t_F(F1 = 0), t_F(F1 = F1*) over their prefactor [-]."""
    t_lo = 0.0
    t_hi = 0.0
    for j in range(x.size):
        u = lo + width * x[j]
        sg = (u * u) * sm
        q = math.sqrt(1.0 - sg * sg)
        sal = sA * (1.0 - 2.0 * sg * sg) - cA * 2.0 * sg * q
        p = (w[j] * width) * math.sqrt(kk + sal * sal) / q
        aj = (cA * q + sA * sg) / c1
        bj = (sA * q - cA * sg) / c2
        P[off + j] = p
        d[off + j] = aj - bj
        b[off + j] = bj
        t_lo += p / math.sqrt(bj)
        t_hi += p / math.sqrt(aj)
    return t_lo, t_hi


@njit(cache=True, nogil=True, fastmath=_NODE_MATH, error_model="numpy")
def _line_sums(P, d, b, n, lam):
    """(sum P h^-1/2, sum P d h^-3/2, sum P d^2 h^-5/2) with h = b + lambda d over the first n nodes: t(lambda) and
    its first two derivatives over their prefactors (1, -1/2, 3/4) [-]."""
    t0 = 0.0
    t1 = 0.0
    t2 = 0.0
    for j in range(n):
        h = b[j] + lam * d[j]
        r = 1.0 / math.sqrt(h)
        pr = P[j] * r
        e = d[j] / h
        t0 += pr
        t1 += pr * e
        t2 += pr * e * e
    return t0, t1, t2


#: The setup of an observation (sines, cosines, F1*, F2*, the tier ratios, the prefactor: Eq. 11-13), compiled from
#: the function the numpy and GPU back-ends call (:mod:`quickrelease.batch._identify_setup`): one definition, the
#: same bits.
_identify_setup_one = _jit(_identify_setup.identify_setup)


@njit(cache=True, nogil=True, error_model="numpy")
def _identify_one(a0, aF, tF, E, kk, m2, L1, x16, w16, x24, w24, near, hard, mass_sq, mass_hard_sq, tol, max_iter,
                  grading, reach, panels, P, d, b):
    """(lambda, F1*, F2*, t_lo, t_hi, status, iterations) of one observation: Halley's method in lambda = F1/F1* on
    the line of Eq. 13 (t(lambda) increasing and convex; cubic convergence, 3-4 steps; Newton's step where Halley's
    denominator is not safely positive), on the rule of the stop-time kernel (graded panels where needed)."""
    sA, cA, sm, c1, c2, F1max, F2max, ratio, msq, pref = _identify_setup_one(a0, aF, E, kk, m2, L1)
    tier = _tier(ratio, msq, near, hard, mass_sq, mass_hard_sq)
    if tier == 2:
        jl = _panel_count(math.sqrt(ratio) if ratio > 0.0 else 0.0, grading, reach, panels)
        jr = _panel_count(0.5 * math.sqrt(msq), grading, reach, panels)
        lo = 0.0
        hi = 0.0
        n = 0
        top = 0.5
        for _ in range(jl):
            bottom = top * grading
            tl, th = _line_nodes(x16, w16, bottom, top - bottom, sm, sA, cA, c1, c2, kk, P, d, b, n)
            lo += tl
            hi += th
            n += x16.size
            top = bottom
        tl, th = _line_nodes(x16, w16, 0.0, top, sm, sA, cA, c1, c2, kk, P, d, b, n)
        lo += tl
        hi += th
        n += x16.size
        top = 0.5
        for _ in range(jr):
            bottom = top * grading
            tl, th = _line_nodes(x16, w16, 1.0 - top, top - bottom, sm, sA, cA, c1, c2, kk, P, d, b, n)
            lo += tl
            hi += th
            n += x16.size
            top = bottom
        tl, th = _line_nodes(x16, w16, 1.0 - top, top, sm, sA, cA, c1, c2, kk, P, d, b, n)
        lo += tl
        hi += th
        n += x16.size
    elif tier == 1:
        lo, hi = _line_nodes(x24, w24, 0.0, 1.0, sm, sA, cA, c1, c2, kk, P, d, b, 0)
        n = x24.size
    else:
        lo, hi = _line_nodes(x16, w16, 0.0, 1.0, sm, sA, cA, c1, c2, kk, P, d, b, 0)
        n = x16.size
    lo *= pref
    hi *= pref
    # an observation within rounding of an end of the feasible interval is that end (F1 = 0 or F2 = 0)
    # (on either side of it: the end is the solution there, to within what rounding can tell)
    if abs(tF - lo) <= _slack(lo, a0, aF, 0.0):
        return 0.0, F1max, F2max, lo, hi, 0, 0
    # (the F1* end's sensitivity to alpha_F near pi/2 widens it outwards only)
    if abs(tF - hi) <= _slack(hi, a0, aF, 0.0) or hi < tF <= hi + _slack(hi, a0, aF, 1.0):
        return 1.0, F1max, F2max, lo, hi, 0, 0
    if tF < lo:
        return math.nan, F1max, F2max, lo, hi, 1, 0
    if tF > hi:
        return math.nan, F1max, F2max, lo, hi, 2, 0
    # start where a one-node model t = lo / sqrt(1 + lambda ((lo / hi)^2 - 1)), exact at both ends, meets t_F
    lam = min(max(((lo / tF) ** 2 - 1.0) / ((lo / hi) ** 2 - 1.0), 0.0), 1.0)
    iterations = 0
    while iterations < max_iter:
        iterations += 1
        t0, t1, t2 = _line_sums(P, d, b, n, lam)
        f = pref * t0 - tF
        slope = -0.5 * pref * t1
        curve = 0.75 * pref * t2
        newton = f / slope
        denom = 1.0 - 0.5 * newton * curve / slope
        step = newton / denom if denom > 0.5 else newton
        new = min(max(lam - step, 0.0), 1.0)
        # converged to tol, or to the rounding floor of lambda (t known to a few ulps)
        done = abs(new - lam) <= max(tol, 8.0 * 2.220446049250313e-16 * pref * t0 / abs(slope))
        lam = new
        if done:
            break
    return lam, F1max, F2max, lo, hi, 0, iterations


@njit(cache=True, nogil=True, parallel=True, error_model="numpy")
def identify_kernel(a0, aF, tF, E, k, m2, L1, x16, w16, x24, w24, near, hard, mass_sq, mass_hard_sq, tol, max_iter,
                    lam_out, F1max_out, F2max_out, tlo_out, thi_out, status_out, iter_out):
    """lambda = F1/F1* of every observation (:func:`_identify_one`; cases with a nonzero status on entry are left
    as they are), over numba's threads in blocks of :data:`BLOCK` cases."""
    n_cases = a0.size
    grading = _kernels.GRADING
    reach = GRADED_REACH
    panels = _kernels.N_PANELS
    n_blocks = (n_cases + BLOCK - 1) // BLOCK
    # one scratch row per block, allocated before the parallel loop: each block's rows are its own whatever thread
    # runs it (tests/test_threads.py's race probe shares rows on purpose and catches it). An np.empty inside the
    # prange body, the layout before, is hoisted into each thread's share of the loop by numba 0.68 and was found not
    # to race; the F1, F2 up to 5e-5 apart between loaded processes seen with it then have no cause established.
    P_rows = np.empty((n_blocks, MAX_NODES))  # three 2-D arrays, so that a row is typed C-contiguous (a row of a
    d_rows = np.empty((n_blocks, MAX_NODES))  # 3-D array was not, and the node loops ran 35% slower)
    b_rows = np.empty((n_blocks, MAX_NODES))
    for blk in prange(n_blocks):
        P = P_rows[blk]
        d = d_rows[blk]
        b = b_rows[blk]
        for i in range(blk * BLOCK, min(n_cases, (blk + 1) * BLOCK)):
            if status_out[i] != 0:
                continue
            lam, F1max, F2max, lo, hi, status, iterations = _identify_one(
                a0[i], aF[i], tF[i], E[i], k[i], m2[i], L1[i], x16, w16, x24, w24, near, hard, mass_sq, mass_hard_sq,
                tol, max_iter, grading, reach, panels, P, d, b)
            lam_out[i] = lam
            F1max_out[i] = F1max
            F2max_out[i] = F2max
            tlo_out[i] = lo
            thi_out[i] = hi
            status_out[i] = status
            iter_out[i] = iterations


_accel = _jit(_kernels.head_hinge_acceleration, acceleration_terms=_jit(_kernels.acceleration_terms))
#: ``_kernels.refine_peak`` compiled as written, its call of ``head_hinge_acceleration`` bound to ``_accel``.
_refine_peak = njit(cache=True, nogil=True, error_model="numpy")(types.FunctionType(
    _kernels.refine_peak.__code__, {**_kernels.refine_peak.__globals__, "head_hinge_acceleration": _accel},
    "refine_peak", _kernels.refine_peak.__defaults__))


@njit(cache=True, nogil=True, error_model="numpy")
def _refined(best, j, n, a0, h, E, s0, c0, A, B, F1, F2, k, m2, L1, which):
    """The best sample j's value, raised to the maximum at a root of the jerk in [a_(j-1), a_j] or
    [a_j, a_(j+1)] when one lies there (``_kernels.refine_peak``)."""
    out = best
    if j > 0:
        out = max(out, _refine_peak(a0 + (j - 1) * h, a0 + j * h, E, s0, c0, A, B, F1, F2, k, m2, L1, which))
    if j < n - 1:
        out = max(out, _refine_peak(a0 + j * h, a0 + (j + 1) * h, E, s0, c0, A, B, F1, F2, k, m2, L1, which))
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def peak_accel_kernel(E, a0, aE, F1, F2, k, m2, L1, n, pu_out, pv_out):
    """Peaks of |u_ddot| and |v_ddot| over [alpha0, alpha_end] (the numpy ``batch._peak_accelerations``):
    n equally spaced angles (sines and cosines by rotation, no trigonometric call per angle) pick the best
    sample; the maximum is then the root of the jerk bracketed by its neighbours (``_kernels.refine_peak``)."""
    for i in range(E.size):
        h = (aE[i] - a0[i]) / (n - 1)
        ch, sh = math.cos(h), math.sin(h)
        s0, c0 = math.sin(a0[i]), math.cos(a0[i])
        s, c = s0, c0
        A = 2.0 * F1[i] * L1[i]
        B = 4.0 * F2[i] * L1[i]
        ml = m2[i] * L1[i]
        best_u = best_v = -1.0
        ju = jv = 0
        for j in range(n):
            K = E[i] - A * (s - s0) - B * (c0 - c)
            d = k[i] + s * s
            rate2 = max(K, 0.0) / (ml * L1[i] * d)
            acc = -rate2 * s * c / d - (2.0 * F2[i] * s + F1[i] * c) / (ml * d)
            pu = abs(L1[i] * (c * rate2 + s * acc))
            pv = abs(L1[i] * (-s * rate2 + c * acc))
            if pu > best_u:
                best_u, ju = pu, j
            if pv > best_v:
                best_v, jv = pv, j
            s, c = s * ch + c * sh, c * ch - s * sh
        args = (E[i], s0, c0, A, B, F1[i], F2[i], k[i], m2[i], L1[i])
        pu_out[i] = _refined(best_u, ju, n, a0[i], h, *args, 0)
        pv_out[i] = _refined(best_v, jv, n, a0[i], h, *args, 1)


#: Every kernel defined in this file (cached by numba under this file's name): flushed together when the
#: modules they inline change (the functions compiled from dynamics and _kernels are stamped with their own files).
KERNELS = (_tier, _friction_nodes, _limit_nodes, _panel_count, _panel_sum, _graded_sum, _stop_one,
           _setup_calls, _setup_vector, stop_kernel_sides, screen_flags, friction_angles, _line_nodes, _line_sums,
           _identify_one, identify_kernel, _refined, peak_accel_kernel)
_refresh_stale_cache(KERNELS)
