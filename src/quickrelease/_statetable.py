"""The state of one release as a function of time, alpha(t), tabulated for many sample times at once.

A record holds up to millions of sample times; inverting the time map (:class:`quickrelease._timemap.TimeMap`,
a few Newton steps on a degree-32 series) at each of them costs microseconds per time and per model
evaluation. During the motion alpha(t) solves a smooth ODE (Eq. 3/4 on the branch alpha_dot > 0), so it is
smooth on the closed interval [0, t_F], stop included. :class:`StateTable` tabulates it on uniform nodes
``t_k = k t_F / M`` with alpha, alpha_dot (the first integral, Eq. 9-10, at the inverted node times) and
alpha_ddot (the equation of motion, Eq. 3/4), and interpolates between nodes with the quintic Hermite
polynomial that matches all three at both ends of the cell (C^2 across nodes; error O(h^6) in alpha, O(h^5)
in alpha_dot). The cell of a time is found by arithmetic on the uniform grid, so evaluating N times costs
about twenty array passes: linear in N with a small constant, independent of the table size.

Accuracy rule: M starts at :data:`START_CELLS` and is doubled until, at every cell's midpoint and quarter
points, the interpolated alpha and alpha_dot differ from the exact values (the time map inverted there) by
at most :data:`TOL` times their largest magnitude over the nodes. alpha_ddot at a time is the equation of
motion applied to the interpolated (alpha, alpha_dot), as the exact path computes it (the polynomial's own
second derivative would lose eps |alpha| / h^2 to rounding). If :data:`MAX_CELLS` cells do not suffice, or
the error stops decreasing, :meth:`StateTable.build` returns None and the caller inverts the time map at
every time.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["StateTable", "ChannelTable", "TOL", "CHANNEL_TOL", "START_CELLS", "MAX_CELLS"]

#: Largest interpolation error at the check points, relative to the largest |alpha|, |alpha_dot| over the nodes.
TOL = 1e-11
START_CELLS = 64
MAX_CELLS = 1 << 16


def _quintic_coefficients(p, d, s, h) -> np.ndarray:
    """Monomial coefficients (in u = (t - t_k)/h, u in [0, 1]) of the quintic Hermite interpolant of each cell
    from the values p, first derivatives d and second derivatives s at the nodes (arrays of M + 1)."""
    p0, p1 = p[:-1], p[1:]
    d0, d1 = d[:-1] * h, d[1:] * h
    s0, s1 = s[:-1] * h * h, s[1:] * h * h
    c0, c1, c2 = p0, d0, 0.5 * s0
    a = p1 - c0 - c1 - c2          # c3 + c4 + c5
    b = d1 - c1 - 2.0 * c2         # 3 c3 + 4 c4 + 5 c5
    e = s1 - 2.0 * c2              # 6 c3 + 12 c4 + 20 c5
    c3 = 10.0 * a - 4.0 * b + 0.5 * e
    c4 = -15.0 * a + 7.0 * b - e
    c5 = 6.0 * a - 3.0 * b + 0.5 * e
    return np.stack([c0, c1, c2, c3, c4, c5], axis=1)


class StateTable:
    """alpha(t), alpha_dot(t) on [0, t_F] by piecewise quintic Hermite interpolation on uniform nodes."""

    def __init__(self, t_end: float, coef: np.ndarray, error: float,
                 acceleration: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> None:
        self.t_end = float(t_end)
        self.acceleration = acceleration
        """alpha_ddot from (alpha, alpha_dot): the equation of motion (Eq. 3/4)."""
        self.coef = coef
        """(M, 6) monomial coefficients of alpha on each cell, in the cell's variable u in [0, 1]."""
        self._rows = np.ascontiguousarray(coef.T)  # (6, M): one gather per coefficient
        self.cells = coef.shape[0]
        self.h = self.t_end / self.cells
        self.error = float(error)
        """The largest relative error found at the check points (of alpha and alpha_dot)."""

    @classmethod
    def build(cls, t_end: float, exact: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
              acceleration: Callable[[np.ndarray, np.ndarray], np.ndarray], tol: float = TOL,
              start: int = START_CELLS, max_cells: int = MAX_CELLS) -> StateTable | None:
        """Tabulate on [0, t_end]; ``exact(t)`` gives (alpha, alpha_dot) at times t (the time map inverted),
        ``acceleration(alpha, alpha_dot)`` alpha_ddot (Eq. 3/4). None if ``max_cells`` cells do not meet ``tol``.
        """
        if not (np.isfinite(t_end) and t_end > 0.0):
            return None
        m = start
        t = np.linspace(0.0, t_end, m + 1)
        a, ad = exact(t)
        add = acceleration(a, ad)
        best = np.inf
        while m <= max_cells:
            h = t_end / m
            coef = _quintic_coefficients(a, ad, add, h)
            # check at the midpoints (the error of alpha peaks there) and the quarter points (that of alpha_ddot,
            # odd about the midpoint, vanishes at it)
            u = np.repeat([[0.5, 0.25, 0.75]], m, axis=0).ravel()
            cell = np.repeat(np.arange(m), 3)
            tc = t[cell] + u * h
            ac, adc = exact(tc)
            addc = acceleration(ac, adc)
            ia, iad, iadd = _horner(coef[cell], u, h)
            err = max(float(np.max(np.abs(ia - ac))) / max(float(np.max(np.abs(a))), 1e-300),
                      float(np.max(np.abs(iad - adc))) / max(float(np.max(np.abs(ad))), 1e-300))
            am, adm, addm = ac[0::3], adc[0::3], addc[0::3]
            if err <= tol:
                return cls(t_end, coef, err, acceleration)
            if err > 0.5 * best and best < 1e-8:  # no longer converging: the rounding of the exact values reached
                return None
            best = err
            # double: the midpoints become nodes
            m *= 2
            t = np.linspace(0.0, t_end, m + 1)
            a = _interleave(a, am)
            ad = _interleave(ad, adm)
            add = _interleave(add, addm)
        return None

    def state(self, t: np.ndarray, acceleration: bool = False) -> tuple[np.ndarray, ...]:
        """alpha [rad], alpha_dot [rad/s] (and alpha_ddot [rad/s^2]) at times t in [0, t_end] (clipped to it)."""
        x = np.clip(np.asarray(t, dtype=float) / self.h, 0.0, float(self.cells))
        k = np.minimum(x.astype(np.intp), self.cells - 1)
        u = x - k
        c0, c1, c2, c3, c4, c5 = (row.take(k) for row in self._rows)
        a = ((((c5 * u + c4) * u + c3) * u + c2) * u + c1) * u + c0
        ad = ((((5.0 * c5) * u + 4.0 * c4) * u + 3.0 * c3) * u + 2.0 * c2) * u + c1
        ad *= 1.0 / self.h
        if not acceleration:
            return a, ad
        # from the equation of motion, not the polynomial's second derivative (which loses eps |alpha| / h^2)
        return a, ad, self.acceleration(a, ad)


def _interleave(nodes: np.ndarray, mids: np.ndarray) -> np.ndarray:
    out = np.empty(nodes.size + mids.size)
    out[0::2], out[1::2] = nodes, mids
    return out


def _horner(c: np.ndarray, u: np.ndarray, h: float, second: bool = True):
    """alpha, alpha_dot (and alpha_ddot) of the cell polynomials ``c`` (N, 6) at local u (N,)."""
    a = ((((c[:, 5] * u + c[:, 4]) * u + c[:, 3]) * u + c[:, 2]) * u + c[:, 1]) * u + c[:, 0]
    ad = (((5.0 * c[:, 5] * u + 4.0 * c[:, 4]) * u + 3.0 * c[:, 3]) * u + 2.0 * c[:, 2]) * u + c[:, 1]
    add = None
    if second:
        add = ((20.0 * c[:, 5] * u + 12.0 * c[:, 4]) * u + 6.0 * c[:, 3]) * u + 2.0 * c[:, 2]
        add = add / (h * h)
    return a, ad / h, add


#: Largest error of a :class:`ChannelTable` at its check points, relative to the channel's range.
CHANNEL_TOL = 1e-11
_DEG = 7
_CHEB = np.cos((2.0 * np.arange(_DEG + 1) + 1.0) * np.pi / (2.0 * (_DEG + 1)))
#: Monomial coefficients (in u in [-1, 1]) from the values at the Chebyshev points of the first kind.
_FROM_VALUES = np.linalg.inv(np.vander(_CHEB, _DEG + 1, increasing=True))


class ChannelTable:
    """Channel model values as smooth functions of time on [lo, hi]: degree-7 polynomials on uniform cells.

    Each cell's polynomial interpolates the channels at the cell's 8 Chebyshev points. Cells are doubled
    (from 32 up to :data:`MAX_CELLS`) until at every cell edge and centre (not interpolation points) each
    channel is within :data:`CHANNEL_TOL` of its range over the points; :meth:`build` returns None otherwise.
    Evaluating N times costs one gather and Horner step per coefficient: about 25 array passes.
    """

    def __init__(self, names, lo: float, hi: float, coef: dict[str, np.ndarray], error: float) -> None:
        self.names = list(names)
        self.lo, self.hi = float(lo), float(hi)
        self.coef = coef
        """name -> (8, M) monomial coefficients per cell in u in [-1, 1]."""
        self.cells = next(iter(coef.values())).shape[1]
        self.h = (self.hi - self.lo) / self.cells
        self.error = float(error)
        """The largest error found at the check points, relative to the channel's range."""

    @classmethod
    def build(cls, f: Callable[[np.ndarray], dict[str, np.ndarray]], names, lo: float, hi: float,
              tol: float = CHANNEL_TOL, start: int = 32, max_cells: int = MAX_CELLS) -> ChannelTable | None:
        """Tabulate ``f(times) -> {name: values}`` on [lo, hi]; None if ``max_cells`` cells do not meet ``tol``."""
        if not (np.isfinite(lo) and np.isfinite(hi) and hi > lo):
            return None
        m, best = start, np.inf
        while m <= max_cells:
            h = (hi - lo) / m
            left = lo + h * np.arange(m)
            nodes = (left[:, None] + 0.5 * h * (_CHEB[None, :] + 1.0)).ravel()
            edges = lo + h * np.arange(m + 1)
            centres = left + 0.5 * h
            values = f(np.concatenate([nodes, edges, centres]))
            coef = {}
            err = 0.0
            for name in names:
                v = values[name]
                vn = v[:nodes.size].reshape(m, _DEG + 1)
                c = _FROM_VALUES @ vn.T  # (8, M)
                coef[name] = c
                scale = max(float(np.ptp(v)), float(np.max(np.abs(v))) * 1e-300, 1e-300)
                at_left = _poly(c, np.full(m, -1.0))
                at_right = _poly(c, np.full(m, 1.0))
                at_centre = _poly(c, np.zeros(m))
                ve, vc = v[nodes.size:nodes.size + m + 1], v[nodes.size + m + 1:]
                e = max(float(np.max(np.abs(at_left - ve[:-1]))), float(np.max(np.abs(at_right - ve[1:]))),
                        float(np.max(np.abs(at_centre - vc))))
                err = max(err, e / scale)
            if err <= tol:
                return cls(names, lo, hi, coef, err)
            if err > 0.5 * best and best < 1e-8:  # no longer converging: rounding reached
                return None
            best = err
            m *= 2
        return None

    def values(self, t: np.ndarray) -> dict[str, np.ndarray]:
        """Each channel at times t in [lo, hi] (clipped to it)."""
        x = np.clip((np.asarray(t, dtype=float) - self.lo) / self.h, 0.0, float(self.cells))
        k = np.minimum(x.astype(np.intp), self.cells - 1)
        u = 2.0 * (x - k) - 1.0
        return {name: _poly(c, u, k) for name, c in self.coef.items()}


def _poly(c: np.ndarray, u: np.ndarray, k: np.ndarray | None = None) -> np.ndarray:
    """Horner on the (8, M) coefficients c, of cell k (default: cell i for the i-th u) at u."""
    rows = c if k is None else [row.take(k) for row in c]
    out = rows[-1] * u
    for row in rows[-2:0:-1]:
        out += row
        out *= u
    out += rows[0]
    return out
