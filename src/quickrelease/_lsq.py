"""Least-squares helpers shared by the fits (the device's record fit and the building's isolation fit)."""

from __future__ import annotations

import numpy as np

__all__ = ["jacobian_covariance"]


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
    inner = np.linalg.pinv(Js.T @ Js, rcond=1e-15, hermitian=True)
    return inner / np.outer(norms, norms)
