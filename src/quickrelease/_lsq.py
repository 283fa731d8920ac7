"""Least-squares helpers shared by the fits (the device's record fit and the building's isolation fit)."""

from __future__ import annotations

import numpy as np

__all__ = ["jacobian_covariance", "unidentified", "identified_covariance"]

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
