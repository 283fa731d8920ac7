"""Argument checks shared by the physics and solvers (arrays or floats)."""

from __future__ import annotations

import math

import numpy as np

from .errors import ParameterError

HALF_PI = 0.5 * math.pi


def _first_bad(value, bad_mask):
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        return float(arr)
    return float(arr[bad_mask][0])


def check_positive(name: str, value, unit: str = ""):
    """Raise ParameterError unless every element of ``value`` is finite and > 0."""
    arr = np.asarray(value, dtype=float)
    bad = ~(np.isfinite(arr) & (arr > 0.0))
    if np.any(bad):
        raise ParameterError(name, _first_bad(value, bad), "(0, inf)", unit)
    return value


def check_nonnegative(name: str, value, unit: str = ""):
    """Raise ParameterError unless every element of ``value`` is finite and >= 0."""
    arr = np.asarray(value, dtype=float)
    bad = ~(np.isfinite(arr) & (arr >= 0.0))
    if np.any(bad):
        raise ParameterError(name, _first_bad(value, bad), "[0, inf)", unit)
    return value


def check_angle(name: str, value):
    """Raise ParameterError unless every element of ``value`` lies in (0, pi/2) [rad]."""
    arr = np.asarray(value, dtype=float)
    bad = ~(np.isfinite(arr) & (arr > 0.0) & (arr < HALF_PI))
    if np.any(bad):
        raise ParameterError(name, _first_bad(value, bad), "(0, pi/2)", "rad")
    return value
