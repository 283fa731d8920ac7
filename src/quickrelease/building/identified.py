"""Whether a record identifies a fitted parameter: the one rule of the building's JSON (``not_identified``,
:func:`quickrelease.studies.building_analysis.physical_estimates`) and of building campaigns (a release left out
of a quantity's laws, :meth:`quickrelease.studies.building_campaign.ReleaseEstimates.identified`).

A parameter is not identified when the fit found it so (standard error inf, no interval: ``"not identified"``),
or when its interval is a profile (or one widened over two minima) that runs over the parameter's whole range
(:data:`~quickrelease.building.isolation_fit.PARAMETER_BOUNDS`), e.g. Constantinou's rate ``a`` [s/m] of a record
whose velocities stay low, or of a slider whose friction does not change with the velocity: [0, 1000] s/m.
"""

from __future__ import annotations

import math

from .isolation_fit import PARAMETER_BOUNDS


def whole_range(fit, name: str) -> bool:
    """Whether ``fit``'s interval of parameter ``name`` is a profile (or one widened over two minima) over the
    parameter's whole range (:data:`PARAMETER_BOUNDS`, in the parameter's own unit)."""
    if name not in PARAMETER_BOUNDS or fit.interval_method.get(name) not in ("profile", "covers two minima"):
        return False
    lo, hi = fit.ci95[name]
    return lo <= PARAMETER_BOUNDS[name][0] and hi >= PARAMETER_BOUNDS[name][1]


def parameter_identified(fit, name: str) -> bool:
    """Whether the record of ``fit`` (an :class:`~quickrelease.building.isolation_fit.IsolationFit`) identifies
    its fitted parameter ``name``: not found "not identified" by the fit, a finite standard error, and not an
    interval over the parameter's whole range (:func:`whole_range`). A parameter the fit held fixed (not among
    its fitted ones) has nothing to identify: True."""
    method = fit.interval_method.get(name)
    if method is None:
        return True
    if method == "not identified":
        return False
    se = getattr(fit, "std_errors", {}).get(name, 0.0)
    return math.isfinite(se) and not whole_range(fit, name)
