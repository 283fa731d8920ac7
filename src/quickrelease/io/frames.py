"""Results as tables: pandas DataFrames and xarray Datasets (pandas and xarray imported on first use).

Column names carry the SI unit as a suffix, as in every file the package writes (``x_record_m``,
``a_model_m_s2``); Dataset variables carry it in ``units`` with a ``long_name`` (CF conventions), on a time
coordinate ``t`` [s] where the result is a time series.

* :func:`fit_columns`, :func:`fit_frame`, :func:`fit_dataset`: a building's record, the fitted model and the
  residuals, channel by channel, on the record's time axis (what ``quickrelease building --out`` writes as
  ``timeseries.csv`` and ``timeseries.nc``); :meth:`quickrelease.building.isolation_fit.IsolationFit.to_pandas` and
  ``to_xarray``.
* :func:`free_vibration_frame`, :func:`free_vibration_dataset`: the building's free vibration
  (:class:`quickrelease.building.model.FreeVibration`) sampled in time.
* :func:`summary_frame`, :func:`summary_dataset`: a result's scalar summary (an identification) as one row, or
  as 0-d variables with their units.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["KIND_UNITS", "fit_columns", "fit_frame", "fit_dataset", "free_vibration_frame",
           "free_vibration_dataset", "summary_frame", "summary_dataset"]

#: A channel kind's unit: (column suffix, UDUNITS unit, what it measures).
KIND_UNITS: dict[str, tuple[str, str, str]] = {
    "x": ("m", "m", "displacement"), "v": ("m_s", "m/s", "velocity"), "a": ("m_s2", "m/s^2", "acceleration"),
}
_ROLES = {"record": "measured", "model": "fitted model (with the channel's offset)",
          "residual": "residual, measured minus model"}


def _time_axis(channels) -> np.ndarray:
    """Every instant at which some channel was sampled, sorted, each once [s]."""
    return np.unique(np.concatenate([np.asarray(c.t, dtype=float) for c in channels])) if channels else np.array([])


def fit_columns(fit) -> dict[str, np.ndarray]:
    """A building fit's record, model and residuals as columns on one time axis: ``t_s`` (every instant at
    which a channel was sampled), then per channel ``<name>_record_<unit>``, ``<name>_model_<unit>`` and
    ``<name>_residual_<unit>`` (unit ``m``, ``m_s`` or ``m_s2`` by the channel's kind). The model is given at
    every instant; a channel's record and residual are NaN where that channel has no sample (channels of
    another logger, at another rate, or with samples missing)."""
    t = _time_axis(fit.channels)
    out: dict[str, np.ndarray] = {"t_s": t}
    for ch in fit.channels:
        suffix = KIND_UNITS[ch.kind][0]
        record = np.full(t.shape, np.nan)
        at = np.searchsorted(t, ch.t)
        record[at] = ch.values
        model = np.asarray(fit.model_values(ch, t), dtype=float)
        out[f"{ch.name}_record_{suffix}"] = record
        out[f"{ch.name}_model_{suffix}"] = model
        out[f"{ch.name}_residual_{suffix}"] = record - model
    return out


def fit_frame(fit):
    """:func:`fit_columns` as a pandas DataFrame indexed by the time ``t_s``."""
    import pandas as pd

    return pd.DataFrame(fit_columns(fit)).set_index("t_s")


def fit_dataset(fit, attrs: Mapping[str, Any] | None = None):
    """:func:`fit_columns` as an ``xarray.Dataset`` on the time coordinate ``t`` [s] (the record's time):
    variables ``<name>_record``, ``<name>_model``, ``<name>_residual`` with ``units`` and ``long_name``; the
    model, its convergence and the estimates (SI) as global attributes, with ``attrs`` added."""
    import xarray as xr

    from .._version import __version__

    columns = fit_columns(fit)
    t = columns.pop("t_s")
    kinds = {ch.name: ch.kind for ch in fit.channels}
    variables = {}
    for column, values in columns.items():
        name, role, _ = _split_column(column, kinds)
        _, unit, what = KIND_UNITS[kinds[name]]
        variables[f"{name}_{role}"] = ("t", values, {"units": unit, "long_name": f"{name}: {what}, {_ROLES[role]}"})
    info: dict[str, Any] = {"title": "quickrelease building record, fitted model and residuals",
                            "Conventions": "CF-1.8", "source": f"quickrelease {__version__}", "model": fit.model,
                            "converged": int(bool(fit.converged)), "mass_kg": float(fit.mass)}
    info.update({f"estimate_{k}": float(v) for k, v in fit.estimates.items()})
    info.update(dict(attrs or {}))
    coords = {"t": ("t", t, {"units": "s", "long_name": "time of the record", "axis": "T"})}
    return xr.Dataset(variables, coords=coords, attrs=info)


def _split_column(column: str, kinds: Mapping[str, str]) -> tuple[str, str, str]:
    """(channel, role, unit suffix) of a :func:`fit_columns` column (channel names may hold underscores)."""
    for name, kind in kinds.items():
        for role in _ROLES:
            suffix = KIND_UNITS[kind][0]
            if column == f"{name}_{role}_{suffix}":
                return name, role, suffix
    raise KeyError(column)


def _motion_columns(motion, t) -> dict[str, np.ndarray]:
    if t is None:
        if np.isfinite(motion.stop_time):  # a while at rest after the stop
            t = np.linspace(0.0, 1.1 * float(motion.stop_time), 2001)
        else:  # still moving: to the horizon (the motion is not computed past it)
            t = np.linspace(0.0, float(motion.horizon), 2001)
    t = np.asarray(t, dtype=float)
    x, v, a = motion.state(t)
    return {"t_s": t, "x_m": np.asarray(x, dtype=float), "v_m_s": np.asarray(v, dtype=float),
            "a_m_s2": np.asarray(a, dtype=float)}


def free_vibration_frame(motion, t=None):
    """The building's free vibration (:class:`quickrelease.building.model.FreeVibration`) as a DataFrame indexed by
    the time since the release ``t_s``: displacement ``x_m``, velocity ``v_m_s``, acceleration ``a_m_s2`` of
    the isolation layer. ``t`` [s]: the instants (default 2001 from the release to 1.1 times the stop time,
    or to the horizon while it still moves there)."""
    import pandas as pd

    return pd.DataFrame(_motion_columns(motion, t)).set_index("t_s")


def free_vibration_dataset(motion, t=None):
    """:func:`free_vibration_frame` as an ``xarray.Dataset`` on the time coordinate ``t`` [s] (variables
    ``x``, ``v``, ``a`` with units and long names; the motion's summary as global attributes)."""
    import xarray as xr

    columns = _motion_columns(motion, t)
    names = {"x_m": ("x", "m", "displacement of the isolation layer"),
             "v_m_s": ("v", "m/s", "velocity of the isolation layer"),
             "a_m_s2": ("a", "m/s^2", "acceleration of the isolation layer")}
    variables = {name: ("t", columns[col], {"units": unit, "long_name": long})
                 for col, (name, unit, long) in names.items()}
    coords = {"t": ("t", columns["t_s"], {"units": "s", "long_name": "time since the release", "axis": "T"})}
    attrs = {k: (int(v) if isinstance(v, bool) else v) for k, v in motion.summary().items()
             if isinstance(v, (int, float, str, bool)) and v is not None}
    return xr.Dataset(variables, coords=coords, attrs=attrs)


def _scalars(summary: Mapping[str, Any]) -> dict[str, Any]:
    """The scalar entries of a summary; a two-number list ``k`` as ``k`` with ``_min``/``_max`` before the unit
    suffix (``feasible_stop_time_s`` -> ``feasible_stop_time_min_s``, ``..._max_s``)."""
    from ..report.display import split_key

    out: dict[str, Any] = {}
    for key, value in summary.items():
        if isinstance(value, (list, tuple)) and len(value) == 2 and all(isinstance(v, (int, float)) for v in value):
            name, _, _ = split_key(key)
            unit = key[len(name):]
            out[f"{name}_min{unit}"], out[f"{name}_max{unit}"] = value
        elif value is None or isinstance(value, (bool, int, float, str)):
            out[key] = value
    return out


def summary_frame(summary: Mapping[str, Any]):
    """A result's scalar summary as a one-row DataFrame (columns keyed with their units, as in the JSON)."""
    import pandas as pd

    return pd.DataFrame([_scalars(summary)])


def summary_dataset(summary: Mapping[str, Any], title: str = ""):
    """A result's scalar summary as an ``xarray.Dataset`` of 0-d variables named without the unit suffix, each
    with ``units`` (UDUNITS; ``1`` when dimensionless) and ``long_name``; text entries as global attributes."""
    import xarray as xr

    from ..report.display import label, split_key

    udunits = {"m/s²": "m/s^2", "rad/s²": "rad/s^2", "N·s/m": "N s/m", "°": "degree", "": "1"}
    variables, attrs = {}, {"title": title} if title else {}
    for key, value in _scalars(summary).items():
        if isinstance(value, bool) or value is None or isinstance(value, str):
            attrs[key] = "" if value is None else (int(value) if isinstance(value, bool) else value)
            continue
        name, unit, _ = split_key(key)
        variables[name] = ((), float(value), {"units": udunits.get(unit, unit), "long_name": label(key)})
    return xr.Dataset(variables, attrs=attrs)
