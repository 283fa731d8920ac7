"""Least-squares helpers shared by the fits (the device's record fit and the building's isolation fit)."""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import OptimizeResult, least_squares

__all__ = ["jacobian_covariance", "unidentified", "identified_covariance", "bounded_least_squares"]

#: Relative cut-off of the eigenvalues of the scaled normal matrix ``Js^T Js`` (diagonal 1): a direction below
#: it is one the record does not see (the pseudo-inverse drops it).
RCOND = 1e-15
#: Share of a parameter's unit vector in the dropped directions above which it is not identified.
NULL_SHARE = 1e-3


def jacobian_covariance(J) -> np.ndarray:
    """``(J^T J)^-1`` of a Jacobian whose columns may differ in scale by many orders of magnitude.

    The parameters of a fit come in their own units (a friction force of 1e5 N beside a damping ratio of 0.05
    and an offset of 1e-3 m), so the columns of J, and the eigenvalues of ``J^T J``, span a range that a
    pseudo-inverse with a relative cut-off reads as rank deficiency: the direction of the small-column
    parameter is cut and its variance comes out 0 (a zero-width interval). The columns are scaled to unit
    norm first (``J = Js D``, D the column norms), ``(J^T J)^+ = D^-1 (Js^T Js)^+ D^-1``: the cut-off then
    acts on the correlations only, where a small eigenvalue does mean a combination the data do not fix.
    """
    J = np.asarray(J, dtype=float)
    norms = np.linalg.norm(J, axis=0)
    norms = np.where(norms > 0.0, norms, 1.0)
    Js = J / norms
    inner = np.linalg.pinv(Js.T @ Js, rcond=RCOND, hermitian=True)
    return inner / np.outer(norms, norms)


def unidentified(J) -> np.ndarray:
    """Which parameters (columns of J) the data do not identify, as a boolean mask.

    A column of zeros (the residuals do not change with the parameter: the yield force of a bilinear record
    that never yields), or a parameter with a share above ``NULL_SHARE`` of its unit vector e_i in the null
    space of the scaled normal matrix ``Js^T Js`` (eigenvalues below ``RCOND`` times the largest: a
    combination of parameters the data do not fix, ``sum_null (v_k . e_i)^2``). The pseudo-inverse gives
    such a parameter a variance of about 0 (its direction is dropped); the truth is that it is unbounded.
    """
    J = np.asarray(J, dtype=float)
    norms = np.linalg.norm(J, axis=0)
    out = ~(norms > 0.0)
    keep = np.flatnonzero(~out)
    if keep.size:
        Js = J[:, keep] / norms[keep]
        w, v = np.linalg.eigh(Js.T @ Js)
        null = w <= RCOND * max(float(w[-1]), 0.0)
        if np.any(null):
            share = np.sum(v[:, null] ** 2, axis=1)
            out[keep[share > NULL_SHARE]] = True
    return out


def identified_covariance(J) -> tuple[np.ndarray, np.ndarray]:
    """``(J^T J)^-1`` over the identified parameters, and the mask of the unidentified ones
    (:func:`unidentified`), whose variance is inf and covariances with the others 0."""
    J = np.asarray(J, dtype=float)
    bad = unidentified(J)
    p = J.shape[1]
    cov = np.zeros((p, p))
    good = np.flatnonzero(~bad)
    if good.size:
        cov[np.ix_(good, good)] = jacobian_covariance(J[:, good])
    cov[bad, bad] = np.inf
    return cov, bad


#: A parameter is held at a bound once the distance to it has shrunk by a ratio in CRAWL_RATIO over CRAWL_STEPS
#: consecutive iterations (:func:`bounded_least_squares`).
CRAWL_STEPS = 3
CRAWL_RATIO = (0.05, 0.8)
#: A held parameter is freed where a step inwards would lower the chi-square (2 cost) by more than this many
#: reduced chi-squares (the residual variance): about 0.014 of its conditional standard error.
RELEASE_GAIN = 1e-4
#: Rounds of holding and freeing at most.
ACTIVE_ROUNDS = 4
#: A solve that crawls down a staircase (each iteration a Jacobian, 2 n evaluations) ends where the cost fell by less
#: than STALL_DROP residual variances over the last STALL_STEPS iterations: a restart of the polish on a pendulum
#: campaign's record took 1 580 iterations (3.5 s) to lower the chi-square by 0.34, less than any noise would notice.
STALL_STEPS = 20
STALL_DROP = 0.01


class _Stall(Exception):
    """Raised inside the Jacobian: the cost fell by less than STALL_DROP residual variances over STALL_STEPS
    iterations; ``x``, ``f`` and ``J`` are the last iterate's point, residuals and Jacobian (free parameters)."""

    def __init__(self, x: np.ndarray, f: np.ndarray, J: np.ndarray) -> None:
        super().__init__("stalled")
        self.x, self.f, self.J = x, f, J


class _Crawl(Exception):
    """Raised inside the Jacobian: parameter ``index`` crawls towards ``bound`` from the iterate ``x``."""

    def __init__(self, index: int, bound: float, x: np.ndarray) -> None:
        super().__init__(index)
        self.index, self.bound, self.x = index, bound, x


def _crawls(history: list[np.ndarray], k: int, bound: float) -> bool:
    """Whether coordinate k of the last CRAWL_STEPS + 1 iterates approached ``bound`` geometrically."""
    d = [abs(h[k] - bound) for h in history[-CRAWL_STEPS - 1:]]
    return all(d[m] > 0.0 and CRAWL_RATIO[0] < d[m + 1] / d[m] < CRAWL_RATIO[1] for m in range(CRAWL_STEPS))


def _gauss_newton(J: np.ndarray, f: np.ndarray) -> np.ndarray:
    """The unconstrained Gauss-Newton step ``-J^+ f`` (columns scaled to unit norm first)."""
    norms = np.linalg.norm(J, axis=0)
    norms = np.where(norms > 0.0, norms, 1.0)
    return -np.linalg.lstsq(J / norms, f, rcond=None)[0] / norms


def bounded_least_squares(fun, x0, jac, lower, upper, *, args=(), tol: float = 1e-8, max_nfev: int | None = None,
                          scale=None, origin=None, xtol: float | None = None, **options) -> OptimizeResult:
    """scipy's bounded ``least_squares`` (trust-region reflective) with an active set: a parameter whose optimum
    lies at its bound is held there instead of approached geometrically.

    TRF's Coleman-Li scaling shortens every step towards a bound in proportion to the distance left: where the
    minimum lies at the bound (a sliders' force of 0, a shape exponent at its limit) the parameter halves its
    distance each iteration, each iteration a Jacobian (2 n residual evaluations by central differences): tens of
    iterations, and on a misfit that is flat along the parameter (0.1 s an evaluation) tens of minutes. Here the
    Jacobian's iterates are watched: a parameter whose distance to a bound shrank by a ratio in ``CRAWL_RATIO``
    over ``CRAWL_STEPS`` iterations, and whose unconstrained Gauss-Newton step from there would cross the bound,
    is set to the bound and held, and the others are solved on; at their solution
    the full gradient ``g = J^T f`` decides, for each held parameter, whether a step inwards lowers the cost: the
    predicted drop ``g_i^2 / (2 J_i^T J_i)`` (chi-square units: twice that) above ``RELEASE_GAIN`` residual
    variances frees it again (from the Newton step inwards), else the bound is the optimum (the Karush-Kuhn-Tucker
    condition up to a drop no estimate would notice). At most ``ACTIVE_ROUNDS`` rounds; a freed parameter is not
    held again. A solve whose cost fell by less than ``STALL_DROP`` residual variances over its last ``STALL_STEPS``
    iterations ends there (status 2, its message says so): on a misfit of steps (a record's samples crossed by
    a stick or a reversal) TRF can crawl for thousands of iterations, each a Jacobian.

    ``scale`` (and ``origin``, default 0): each parameter's typical magnitude, the problem solved in the coordinates
    ``u = (x - origin) / scale``. scipy's tests of ``xtol`` compare the step's norm with ``xtol`` times the norm of
    ``x`` in the parameters' own units (``x_scale`` shapes the trust region only): beside a fluid damper's
    coefficient of 1e6 N (s/m)^alpha a step of 0.3 s in the period is "below" 1e-6 of ``x`` and ends the solve, a
    start 5 000 above the minimum taken for one (a Bouc-Wen + damper record's multi-start: thinned solves ended after
    6-10 evaluations). In ``u`` every parameter's change counts relative to its own magnitude. ``xtol``: the step's
    tolerance where it differs from ``tol`` (which sets ``ftol`` and ``gtol``).

    Returns scipy's OptimizeResult over all the parameters (``x``, ``fun``, ``cost``, ``jac`` (the full Jacobian at
    ``x`` where a parameter was held), ``nfev`` and ``njev`` over every round, ``status``, ``success``, ``message``)
    and ``held``, the indices held at a bound at the end.
    """
    if scale is not None:
        s = np.asarray(scale, dtype=float)
        o = np.zeros_like(s) if origin is None else np.asarray(origin, dtype=float)
        if not (s.shape == np.shape(x0) and np.all(np.isfinite(s)) and np.all(s > 0.0) and np.all(np.isfinite(o))):
            raise ValueError(f"scale must be finite and positive, one per parameter (got {scale!r})")
        r = bounded_least_squares(lambda u, *a: fun(o + s * u, *a), (np.asarray(x0, dtype=float) - o) / s,
                                  lambda u, *a: jac(o + s * u, *a) * s, (np.asarray(lower, dtype=float) - o) / s,
                                  (np.asarray(upper, dtype=float) - o) / s, args=args, tol=tol, max_nfev=max_nfev,
                                  xtol=xtol, **options)
        r.x = o + s * r.x
        r.jac = r.jac / s
        if getattr(r, "grad", None) is not None:
            r.grad = r.grad / s
        return r
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    x = np.asarray(x0, dtype=float).copy()
    n = x.size
    held: dict[int, float] = {}
    freed: set[int] = set()
    nfev = njev = 0
    for round_ in range(ACTIVE_ROUNDS + 1):
        free = np.array([i for i in range(n) if i not in held], dtype=int)
        history: list[np.ndarray] = []
        calls: list = [0]
        start = x.copy()

        def full(y, free=free, base=start):
            z = base.copy()
            z[free] = y
            return z

        def f(y, *a, full=full, calls=calls):
            calls[0] += 1
            calls[1:] = [np.array(y), fun(full(y), *a)]  # the residuals of the last iterate (TRF asks the
            return calls[2]  # Jacobian where it has just evaluated them)

        costs: list[float] = []

        def j(y, *a, full=full, free=free, history=history, calls=calls, watch=round_ < ACTIVE_ROUNDS, costs=costs):
            z = full(y)
            history.append(z)
            J = jac(z, *a)[:, free]
            known = len(calls) == 3 and np.array_equal(calls[1], y)  # the residuals at y were just evaluated
            if known:
                f = calls[2]
                costs.append(float(f @ f))
                if len(costs) > STALL_STEPS:  # (the chi-square's fall over the window, in residual variances)
                    variance = costs[-1] / max(f.size - n, 1)
                    if costs[-1 - STALL_STEPS] - costs[-1] < STALL_DROP * max(variance, 1e-300):
                        raise _Stall(np.array(y), f, J)
            if watch and len(history) > CRAWL_STEPS and known:
                crawling = [(k, b) for k, i in enumerate(free) if i not in freed for b in (lo[i], hi[i])
                            if math.isfinite(b) and _crawls(history, i, b)]
                if crawling:  # held only where the Gauss-Newton step would cross the bound (else it converges)
                    step = _gauss_newton(J, calls[2])
                    for k, b in crawling:
                        if (y[k] + step[k] - b) * (y[k] - b) <= 0.0:
                            raise _Crawl(int(free[k]), float(b), z)
            return J

        budget = None if max_nfev is None else max(max_nfev - nfev, 1)
        try:
            r = least_squares(f, x[free], jac=j, bounds=(lo[free], hi[free]), args=args,
                              xtol=tol if xtol is None else xtol, ftol=tol, gtol=tol, max_nfev=budget, **options)
        except _Stall as st:
            njev += len(history)
            nfev += calls[0]
            r = OptimizeResult(x=st.x, fun=st.f, cost=0.5 * float(st.f @ st.f), jac=st.J, grad=st.J.T @ st.f,
                               nfev=0, njev=0, status=2, success=True, optimality=float(np.max(np.abs(st.J.T @ st.f))),
                               message=f"the cost fell by less than {STALL_DROP:g} residual variances over "
                                       f"{STALL_STEPS} iterations (a staircase)")
        except _Crawl as c:
            njev += len(history)
            nfev += calls[0]
            x = c.x.copy()
            x[c.index] = c.bound
            held[c.index] = c.bound
            continue
        nfev += r.nfev
        njev += r.njev or 0
        x = full(r.x)
        if not held:
            r.x, r.held, r.nfev, r.njev = x, [], nfev, njev
            return r
        J = np.ascontiguousarray(jac(x, *args))  # (row-major: the gradient's and the result's arithmetic whatever
        njev += 1  # the layout jac builds its columns in)
        g = J.T @ r.fun
        variance = 2.0 * float(r.cost) / max(r.fun.size - n, 1)
        out = []
        for i, b in held.items():
            inward = 1.0 if b == lo[i] else -1.0
            h = float(J[:, i] @ J[:, i])
            if g[i] * inward < 0.0 and h > 0.0 and g[i] ** 2 / h > RELEASE_GAIN * max(variance, 1e-300):
                x[i] = min(max(b - g[i] / h, lo[i]), hi[i])
                out.append(i)
        if not out or round_ == ACTIVE_ROUNDS:
            return OptimizeResult(x=x, fun=r.fun, cost=r.cost, jac=J, grad=g, nfev=nfev, njev=njev, status=r.status,
                                  success=r.success, message=r.message, optimality=r.optimality,
                                  active_mask=np.array([0 if i not in held else (-1 if held[i] == lo[i] else 1)
                                                        for i in range(n)]),
                                  held=sorted(held))
        for i in out:
            del held[i]
            freed.add(i)
    raise AssertionError("unreachable")  # pragma: no cover
