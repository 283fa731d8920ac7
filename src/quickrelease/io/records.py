"""Measured records of a release: channels, their model values, and reading them from files.

A record is a table of time and one or more channels measured on the device during a test:

========== ===================================================== ==========
channel    what                                                  SI unit
========== ===================================================== ==========
alpha      bar angle (e.g. from video)                           rad
alpha_dot  bar angular velocity (e.g. a gyroscope on a bar)      rad/s
u          retraction of a head along the rail (Table 4)         m
v          outward opening of a central hinge (Table 4)          m
u_dot      head velocity                                         m/s
v_dot      central hinge velocity                                m/s
a_head     head acceleration along the rail, u_ddot (Table 4)    m/s^2
a_hinge    central hinge acceleration, v_ddot (Table 4)          m/s^2
========== ===================================================== ==========

The case file maps columns to channels and gives each channel's unit (``[record]``, see
:func:`parse_record_spec`); :func:`load_record` reads the file (CSV, or any table pandas reads:
Parquet, Feather, Excel, JSON), converts every channel to SI, drops rows without a time (reported),
keeps missing samples out of each channel (reported, never interpolated over), and checks the time
is increasing. Errors name the file and the column.

Before the release the device rests at alpha0 (u = v = 0, no motion); :func:`channel_model` gives the
model value of each channel from the state (alpha, alpha_dot, alpha_ddot).
"""

from __future__ import annotations

import functools
import math
import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..device import kinematics
from ..device.dynamics import angular_acceleration
from ..errors import QuickReleaseError
from ..units import parse_quantity
from .timebase import clipped_samples, jitter_misfit, merge_repeated_times, time_base

__all__ = [
    "CHANNELS", "DISPLACEMENT_CHANNELS", "RecordError", "ChannelSpec", "RecordSpec", "Channel", "Record",
    "RATE_OF", "channel_model", "release_channels", "parse_record_spec", "load_record", "read_table", "detect_release",
    "record_origin", "shifted_record",
    "record_files",
]

#: Channel name -> (quantity kind, SI unit, description).
CHANNELS: dict[str, tuple[str, str, str]] = {
    "alpha": ("angle", "rad", "bar angle alpha (e.g. from video)"),
    "alpha_dot": ("angular_velocity", "rad/s", "bar angular velocity"),
    "u": ("length", "m", "head retraction u along the rail (Table 4)"),
    "v": ("length", "m", "central hinge opening v (Table 4)"),
    "u_dot": ("velocity", "m/s", "head velocity"),
    "v_dot": ("velocity", "m/s", "central hinge velocity"),
    "a_head": ("acceleration", "m/s^2", "head acceleration along the rail, u_ddot (Table 4)"),
    "a_hinge": ("acceleration", "m/s^2", "central hinge acceleration, v_ddot (Table 4)"),
}
#: Channels that carry a constant offset by default (a sensor zero is never exactly zero).
DISPLACEMENT_CHANNELS = ("alpha", "u", "v")


class RecordError(QuickReleaseError):
    """A record file or its channel mapping is unusable; the message names the file and the column."""


def channel_model(name: str, alpha, alpha_dot, alpha_ddot, alpha0: float, L1: float) -> np.ndarray:
    """Model value of channel ``name`` from the state (Tables 4-5) [SI unit of the channel].

    Parameters
    ----------
    alpha, alpha_dot, alpha_ddot : array
        Angle [rad], angular velocity [rad/s] and acceleration [rad/s^2] at the sample times.
    alpha0 : float
        Angle at release [rad] (u and v are measured from it).
    L1 : float
        Bar length [m].
    """
    if name == "alpha":
        return np.asarray(alpha, dtype=float)
    if name == "alpha_dot":
        return np.asarray(alpha_dot, dtype=float)
    if name == "u":
        return kinematics.retraction(alpha, alpha0, L1)
    if name == "v":
        return kinematics.opening(alpha, alpha0, L1)
    if name == "u_dot":
        return kinematics.retraction_rate(alpha, alpha_dot, L1)
    if name == "v_dot":
        return kinematics.opening_rate(alpha, alpha_dot, L1)
    if name == "a_head":
        return kinematics.retraction_acceleration(alpha, alpha_dot, alpha_ddot, L1)
    if name == "a_hinge":
        return kinematics.opening_acceleration(alpha, alpha_dot, alpha_ddot, L1)
    raise QuickReleaseError(f"unknown channel {name!r}; valid: {', '.join(CHANNELS)}")


#: Rate channels and the displacement channel they are the first (velocities) or second (accelerations)
#: derivative of (see :func:`release_channels` on sampling windows).
RATE_OF = {"alpha_dot": "alpha", "u_dot": "u", "v_dot": "v", "a_head": "u", "a_hinge": "v"}
_ACCELERATIONS = ("a_head", "a_hinge")
#: Gauss-Legendre nodes and weights on [0, 1] for the window averages of velocities.
#: Sample times per block of :func:`release_channels` (each block needs up to 8 window times per sample).
_BLOCK = 1 << 17
#: Samples within the motion from which on :func:`release_channels` interpolates a channel table.
_TABLE_MIN = 2048
_GL_Y, _GL_W = (lambda x, w: (0.5 * (x + 1.0), 0.5 * w))(*np.polynomial.legendre.leggauss(4))


def _accelerations(fi, alpha, alpha_dot):
    return angular_acceleration(alpha, alpha_dot, fi.F1, fi.F2, fi.m1, fi.m2, fi.L1, fi.c)


def release_channels(names, t, release_time: float, release, window: float = 0.0, *,
                     exact: bool = False) -> dict[str, np.ndarray]:
    """Model values of the channels ``names`` at record times ``t`` for a release at ``release_time``.

    ``release`` is the energy solution of the release (:class:`quickrelease.device.solvers.FirstIntegral`). The
    device rests at alpha0 before the release and at the end angle after the motion; in between the
    state comes from the first integral (Eq. 9-10) and the angular acceleration from the equation of
    motion (Eq. 3/4), which is 0 at rest (friction balances inertia). SI units throughout.

    With ``window`` > 0 (the sampling interval Delta [s]), rate channels are the average of the quantity
    over a triangular window of +-Delta about each sample, the simplest model of an anti-aliased
    acquisition: a velocity is ``(1/Delta^2) int_0^Delta (x(t + tau) - x(t - tau)) dtau`` (4-point Gauss)
    and an acceleration ``(x(t + Delta) - 2 x(t) + x(t - Delta)) / Delta^2``, both exact for the window,
    with x the displacement it derives from. For accelerations x has the velocity jump of the model's
    instantaneous release removed (before it, x continues with the initial velocity): a real release takes
    milliseconds and no accelerometer records a Dirac impulse. The model's jumps (the velocity at the
    release, the acceleration at the release and at the stop) then reach the samples continuously and
    always through a sample in transition, so a fit can move the release and the stop across samples.
    Displacement channels are point values.

    The state at the times within the motion comes from the release's interpolated state table
    (:meth:`~quickrelease.device.solvers.FirstIntegral.state_at_many`: cost linear in the number of times, alpha,
    alpha_dot and alpha_ddot within 1e-9 of their largest values); ``exact=True`` inverts the time map at every time.
    """
    s = np.asarray(t, dtype=float) - release_time
    if exact:
        return _direct(names, s, release, window, exact=True)
    return _tabulated(names, s, release, window)


def _tabulated(names, s, fi, window: float) -> dict[str, np.ndarray]:
    """:func:`release_channels` at a cost linear in the number of samples with a small constant
    (:class:`ReleaseChannels` on every sample)."""
    return ReleaseChannels(names, s, 0.0, fi, window)(slice(None))


class ReleaseChannels:
    """:func:`release_channels` (``exact=False``) prepared once for a time axis ``t``, to evaluate on slices of it.

    ``ReleaseChannels(names, t, release_time, release, window)(rows)[name]`` equals
    ``release_channels(names, t, release_time, release, window)[name][rows]`` element by element: the
    choices that depend on the whole axis (whether a channel table is built, the table itself) are made here,
    and each sample is then computed on its own. A caller that walks the axis in slices (the record fit's
    streamed stages, :mod:`quickrelease.studies.fit`) needs memory of the order of a slice, not of the axis.

    Samples whose window lies entirely at rest before the release or after the stop take that rest's
    constant value; samples whose window lies entirely within the motion, where every channel is a smooth
    function of time, take it from a :class:`~quickrelease._statetable.ChannelTable` (piecewise degree-7
    polynomials on uniform cells, each channel within :data:`~quickrelease._statetable.CHANNEL_TOL` of its
    range, built from :func:`_direct`); the few samples whose window reaches across the release or the stop
    are computed directly. With fewer than :data:`_TABLE_MIN` samples within the motion every sample is
    computed directly.
    """

    def __init__(self, names, t, release_time: float, release, window: float = 0.0) -> None:
        from .._statetable import ChannelTable

        self.names, self.t, self.release_time, self.fi, self.window = list(names), t, release_time, release, window
        self.t_stop = release.stop_time()
        lo, hi = window, self.t_stop - window
        inside = 0
        for i in range(0, np.size(t), _BLOCK):  # in blocks: no temporary of the axis' size
            s = np.asarray(t[i:i + _BLOCK], dtype=float) - release_time
            inside += int(np.count_nonzero((s > lo) & (s < hi)))
        self.table = None
        if inside >= _TABLE_MIN:
            self.table = ChannelTable.build(lambda x: _direct(self.names, x, release, window, exact=False),
                                            self.names, lo, hi)
        if self.table is not None:  # the two rests' values
            self.rest = _direct(self.names, np.array([-window - 1.0, self.t_stop + window + 1.0]), release, window,
                                exact=False)

    def __call__(self, rows) -> dict[str, np.ndarray]:
        """The channels at the samples ``t[rows]`` (a slice or an index array)."""
        names, fi, window = self.names, self.fi, self.window
        s = np.asarray(self.t[rows], dtype=float) - self.release_time
        if self.table is None:
            return _direct(names, s, fi, window, exact=False)
        t_stop = self.t_stop
        inside = (s > window) & (s < t_stop - window)
        pre = s <= -window
        post = s > t_stop + window
        edge = ~(inside | pre | post)
        rest = self.rest
        values = self.table.values(s[inside])
        out = {}
        for name in names:
            v = np.empty(s.shape)
            v[pre], v[post] = rest[name][0], rest[name][1]
            v[inside] = values[name]
            out[name] = v
        if np.any(edge):
            direct = _direct(names, s[edge], fi, window, exact=False)
            for name in names:
                out[name][edge] = direct[name]
        return out


def _direct(names, s, fi, window: float, exact: bool) -> dict[str, np.ndarray]:
    """:func:`release_channels` at times ``s`` since the release, every time evaluated (in blocks)."""
    if s.size > _BLOCK:  # in blocks: the window times of a block stay small in memory
        blocks = [_direct(names, s[i:i + _BLOCK], fi, window, exact) for i in range(0, s.size, _BLOCK)]
        return {name: np.concatenate([b[name] for b in blocks]) for name in names}
    if not exact and window > 0.0 and any(name in _ACCELERATIONS for name in names):
        accel = [name for name in names if name in _ACCELERATIONS]
        out = _window_accelerations(accel, s, fi, window)
        rest = [name for name in names if name not in _ACCELERATIONS]
        if rest:
            out.update(_direct(rest, s, fi, window, exact))
        return {name: out[name] for name in names}
    n = s.size
    point = [name for name in names if window <= 0.0 or name not in RATE_OF]
    velocities = [name for name in names if name not in point and name not in _ACCELERATIONS]
    accelerations = [name for name in names if name not in point and name in _ACCELERATIONS]
    # one inversion of the time map for every time needed
    parts = [s] if point or accelerations else []
    if accelerations:
        parts += [s - window, s + window]
    if velocities:
        parts += [s + window * y for y in _GL_Y] + [s - window * y for y in _GL_Y]
    times = np.concatenate(parts)
    alpha, alpha_dot = fi.state_at(times) if exact else fi.state_at_many(times)
    out: dict[str, np.ndarray] = {}
    if point:
        a, ad = alpha[:n], alpha_dot[:n]
        add = _accelerations(fi, a, ad)
        for name in point:
            out[name] = channel_model(name, a, ad, add, fi.alpha0, fi.L1)
    k = 1 if point or accelerations else 0
    if accelerations:
        # the velocity jump removed: before the release the displacement continues at the initial rate
        slopes = {name: channel_model(RATE_OF[name] + "_dot", np.full(1, fi.alpha0), np.full(1, fi.alpha_dot0), 0.0,
                                      fi.alpha0, fi.L1)[0] for name in accelerations}
        x = {}
        for j, part in enumerate((slice(0, n), slice(n, 2 * n), slice(2 * n, 3 * n))):
            rest = times[part] <= 0.0
            for name in accelerations:
                value = channel_model(RATE_OF[name], alpha[part], alpha_dot[part], 0.0, fi.alpha0, fi.L1)
                x[(name, j)] = np.where(rest, slopes[name] * times[part], value)
        for name in accelerations:
            out[name] = (x[(name, 2)] - 2.0 * x[(name, 0)] + x[(name, 1)]) / window**2
        k = 3
    if velocities:
        m = _GL_Y.size
        plus = [slice((k + j) * n, (k + j + 1) * n) for j in range(m)]
        minus = [slice((k + m + j) * n, (k + m + j + 1) * n) for j in range(m)]
        for name in velocities:
            base = RATE_OF[name]
            acc = np.zeros(n)
            for w, sp, sm in zip(_GL_W, plus, minus, strict=True):
                acc += w * (channel_model(base, alpha[sp], alpha_dot[sp], 0.0, fi.alpha0, fi.L1)
                            - channel_model(base, alpha[sm], alpha_dot[sm], 0.0, fi.alpha0, fi.L1))
            out[name] = acc / window
    return {name: out[name] for name in names}


@functools.cache
def _triangle_rule(nodes: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Gauss nodes y and weights W on [0, 1] for the weight (1 - y): ``int_0^1 (1 - y) g(y) dy = sum W g(y)``,
    exact for g of degree 2 nodes - 1 (Gauss-Jacobi, alpha = 1, beta = 0, mapped from [-1, 1])."""
    from scipy.special import roots_jacobi

    x, w = roots_jacobi(nodes, 1.0, 0.0)
    return 0.5 * (x + 1.0), 0.25 * w


def _window_accelerations(names, s, fi, window: float) -> dict[str, np.ndarray]:
    """Acceleration channels averaged over the triangular window of +-Delta, without the second difference.

    ``(x(s + Delta) - 2 x(s) + x(s - Delta)) / Delta^2 = int_0^1 (1 - y) (x''(s + Delta y) + x''(s - Delta y)) dy``
    with x'' the instantaneous acceleration (Table 4 from alpha, alpha_dot, alpha_ddot; 0 at rest). Where the
    window lies within the motion or within a rest, x'' is smooth over it and a 4-node Gauss rule for the
    weight (1 - y) gives the average with error of order (Delta / T)^8 (T the time scale of the motion),
    free of the cancellation that makes the second difference lose ``eps / Delta^2`` (1e-6 of the range at
    50 kHz). Samples whose window reaches across the release or the stop (a jump of x'', or of x' at the
    geometric limit) are integrated piecewise (:func:`_edge_accelerations`).
    """
    y, weights = _triangle_rule()
    t_stop = fi.stop_time()
    n = s.size
    edge = ((s - window < 0.0) & (s + window > 0.0)) | ((s - window < t_stop) & (s + window > t_stop))
    smooth = np.nonzero(~edge)[0]
    ss = s[smooth]
    times = np.concatenate([ss + window * y[j] for j in range(y.size)] + [ss - window * y[j] for j in range(y.size)])
    alpha, alpha_dot, alpha_ddot = fi.state_at_many(times, acceleration=True)
    out = {}
    m = ss.size
    for name in names:
        inst = channel_model(name, alpha, alpha_dot, alpha_ddot, fi.alpha0, fi.L1)
        acc = np.zeros(m)
        for j, wj in enumerate(weights):
            acc += wj * (inst[j * m:(j + 1) * m] + inst[(y.size + j) * m:(y.size + j + 1) * m])
        full = np.empty(n)
        full[smooth] = acc
        out[name] = full
    rows = np.nonzero(edge)[0]
    if rows.size:
        values = _edge_accelerations(names, s[rows], fi, window)
        for name in names:
            out[name][rows] = values[name]
    return out


#: Gauss-Legendre nodes and weights on [0, 1] for the pieces of a window cut by the release or the stop.
_GL8_Y, _GL8_W = (lambda x, w: (0.5 * (x + 1.0), 0.5 * w))(*np.polynomial.legendre.leggauss(8))


def _edge_accelerations(names, s: np.ndarray, fi, window: float) -> dict[str, np.ndarray]:
    """The window average of :func:`_window_accelerations` for samples at times ``s`` whose window reaches across
    the release or the stop: each half of a sample's window is cut at them and each smooth piece integrated by
    8-point Gauss-Legendre (the weight (1 - y) included); at the geometric limit the velocity drops to 0 at
    the stop, a Dirac impulse of x'' whose weight is the velocity just before it. The states of every sample's
    nodes come from one evaluation of the motion (a few samples per call, each once its own evaluation)."""
    t_stop = fi.stop_time()
    pieces_t, pieces_w, bounds = [], [], [0]
    for si in s.tolist():
        for side in (1.0, -1.0):
            cuts = sorted({0.0, 1.0} | {y for y in ((0.0 - si) * side / window, (t_stop - si) * side / window)
                                        if 0.0 < y < 1.0})
            for a, b in zip(cuts[:-1], cuts[1:], strict=False):
                y = a + (b - a) * _GL8_Y
                pieces_t.append(si + side * window * y)
                pieces_w.append((b - a) * _GL8_W * (1.0 - y))
        bounds.append(sum(p.size for p in pieces_t))
    times, weights = np.concatenate(pieces_t), np.concatenate(pieces_w)
    moving = (times > 0.0) & (times <= t_stop)
    alpha, alpha_dot = fi.state_at(times)
    alpha_ddot = np.where(moving, angular_acceleration(alpha, np.maximum(alpha_dot, 1e-300), fi.F1, fi.F2, fi.m1,
                                                       fi.m2, fi.L1, fi.c), 0.0)
    impulse = fi.geometric_limit and bool(np.any(np.abs(t_stop - s) < window))
    if impulse:  # the velocity's drop to 0 at the flat rhombus
        a_F, ad_F = fi.state_at(np.array([t_stop]))
    out = {}
    for name in names:
        inst = np.where(moving, channel_model(name, alpha, alpha_dot, alpha_ddot, fi.alpha0, fi.L1), 0.0)
        value = np.array([float(weights[lo:hi] @ inst[lo:hi]) for lo, hi in zip(bounds[:-1], bounds[1:], strict=True)])
        if impulse:
            v_F = float(channel_model(RATE_OF[name] + "_dot", a_F, ad_F, 0.0, fi.alpha0, fi.L1)[0])
            near = np.abs(t_stop - s) < window
            value[near] -= (1.0 - np.abs(t_stop - s[near]) / window) / window * v_F
        out[name] = value
    return out


# -- the mapping in the case file --------------------------------------------------------------------

@dataclass(frozen=True)
class ChannelSpec:
    """How one channel is read: its column, unit, scale, noise level and whether it has an offset."""

    name: str
    column: str
    unit: str
    """Unit of the column's numbers (pint syntax); the channel's SI unit when not given."""
    factor: float
    """SI value of one ``unit`` times ``scale``."""
    noise: float | None = None
    """Noise standard deviation [SI]; None: estimated from the pre-release segment."""
    offset: bool = False
    """Estimate a constant offset of this channel."""
    drift: bool = False
    """Estimate a linear drift of its zero too (the building's channels only: ``drift = true``)."""
    file: Path | None = None
    """A file of its own (time in the same column name unless ``time_column`` is given), else the record's file."""
    time_column: str | None = None
    """The time column of the channel's own file (its own time axis and sampling rate); None: the record's
    time axis (the record's time column, row by row)."""
    time_factor: float = 1.0
    """SI value of one unit of ``time_column`` [s]."""


@dataclass(frozen=True)
class RecordSpec:
    """The ``[record]`` table of a case file, validated (the data are read by :func:`load_record`)."""

    file: Path
    time_column: str
    time_factor: float
    """SI value of one unit of the time column [s]."""
    channels: dict[str, ChannelSpec]
    release_time: float | None = None
    """Start value of the release instant [s, record time], else detected."""
    source: str = "<record>"
    """The case file the mapping came from (for messages)."""
    duplicates: str = "merge"
    """Rows that repeat the time stamp of the row before: ``"merge"`` (one sample, the rows' values
    averaged, said in a note) or ``"refuse"`` (an error naming the row)."""
    clipped: str = "exclude"
    """Clipped samples (:func:`quickrelease.io.timebase.clipped_samples`): ``"exclude"`` (left out like missing
    samples, said in a note) or ``"keep"``."""
    spikes: str = "keep"
    """The building's record only: ``"exclude"`` has the fit leave out the samples its residuals show as
    spikes (``fit_isolation(exclude_spikes=True)``), ``"keep"`` (default) fits every sample."""


_CHANNEL_KEYS = ("column", "unit", "noise", "offset", "drift", "scale", "file", "time")
_RECORD_KEYS = ("file", "time", "release_time", "channels", "duplicates", "clipped", "spikes")
_CHOICES = {"duplicates": ("merge", "refuse"), "clipped": ("exclude", "keep"), "spikes": ("keep", "exclude")}


def _time_spec(time: Any, where: str) -> tuple[str, float]:
    """A ``time`` entry: a column name in seconds, or ``{column, unit}`` -> (column, SI value of its unit)."""
    if isinstance(time, str):
        return time, 1.0
    if isinstance(time, dict) and set(time) <= {"column", "unit"} and isinstance(time.get("column"), str):
        return time["column"], _unit_factor(str(time.get("unit", "s")), "time", f"{where}.unit")
    raise RecordError(f"{where} = {time!r}: expected a column name or {{column = ..., unit = ...}}")


def _unit_factor(unit: str, kind: str, where: str) -> float:
    """SI value of one ``unit`` of a quantity of ``kind``; RecordError naming ``where`` if it is not one."""
    try:
        return parse_quantity(f"1 {unit}", kind, where)
    except QuickReleaseError as exc:
        _, _, reason = str(exc).partition(" has dimension ")
        reason = f"has dimension {reason}" if reason else f"not a unit ({exc})"
        raise RecordError(f"{where} = {unit!r}: {reason}") from None


def parse_record_spec(table: Any, source: str, base: Path, *, channels: dict[str, tuple[str, str, str]] | None = None,
                      offsets: tuple[str, ...] | None = None, section: str = "record",
                      drifts: bool = False) -> RecordSpec:
    """Validate the ``[record]`` table of a case file.

    ``file`` (relative to the case file), ``time`` (a column name in seconds, or a table
    ``{column, unit}``), optional ``release_time`` (a start value), and ``[record.channels]``: for each
    channel of :data:`CHANNELS` a column name (SI unit) or a table with ``column`` and optionally
    ``unit``, ``noise`` (standard deviation, with units), ``offset`` (bool: estimate a constant offset;
    default true for alpha, u, v), ``scale`` (a factor, e.g. -1 for a reversed sensor axis), ``file``
    (a separate file; the record's time column, row by row, unless it gives its own) and ``time`` (with
    ``file``: that file's own time column, a name or ``{column, unit}``; the channel then has its own time
    axis, length and sampling rate).

    ``channels`` (name -> (quantity kind, SI unit, description)), ``offsets`` (the channels with an offset
    by default) and ``section`` (the table's name in messages) default to the device's record; the
    building's record (``[building.record]``) passes its own, and ``drifts=True``: its channels may also say
    ``drift = true`` (a linear drift of the sensor's zero, fitted beside the offset) and the record
    ``spikes = "exclude"`` (the fit leaves out the samples its residuals show as spikes).
    """
    channels = CHANNELS if channels is None else channels
    offsets = DISPLACEMENT_CHANNELS if offsets is None else offsets
    where = f"{source} [{section}]"
    if not isinstance(table, dict):
        raise RecordError(f"{where}: expected a table")
    unknown = sorted(set(table) - set(_RECORD_KEYS))
    if unknown:
        raise RecordError(f"{where}: unknown key {unknown[0]!r}; valid: {', '.join(_RECORD_KEYS)}")
    for key in ("file", "time", "channels"):
        if key not in table:
            raise RecordError(f"{where}: missing key {key!r}")
    if not isinstance(table["file"], str):
        raise RecordError(f"{where}: file = {table['file']!r}: expected a path")
    file = Path(table["file"])
    file = file if file.is_absolute() else base / file
    time_column, time_factor = _time_spec(table["time"], f"{where} time")
    release = None
    if "release_time" in table:
        try:
            release = parse_quantity(table["release_time"], "time", "release_time")
        except QuickReleaseError as exc:
            raise RecordError(f"{where}: {exc}") from None
    choices = {}
    for key, valid in _CHOICES.items():
        choices[key] = table.get(key, valid[0])
        if choices[key] not in valid:
            raise RecordError(f"{where}: {key} = {choices[key]!r}: expected " + " or ".join(map(repr, valid)))
    if choices["spikes"] != "keep" and not drifts:
        raise RecordError(f"{where}: spikes = {choices['spikes']!r}: spikes are excluded by the building's fit "
                          "only ([building.record])")
    channels_table = table["channels"]
    if not isinstance(channels_table, dict) or not channels_table:
        raise RecordError(f"{where}: channels: expected a table mapping channels ({', '.join(channels)}) to columns")
    specs = {}
    for name, entry in channels_table.items():
        specs[name] = _channel_spec(name, entry, f"{where} channels.{name}", base, channels, offsets, drifts)
    return RecordSpec(file=file, time_column=time_column, time_factor=time_factor, channels=specs,
                      release_time=release, source=source, **choices)


def _channel_spec(name: str, entry: Any, where: str, base: Path, channels: dict[str, tuple[str, str, str]],
                  offsets: tuple[str, ...], drifts: bool = False) -> ChannelSpec:
    if name not in channels:
        raise RecordError(f"{where}: unknown channel {name!r}; valid: {', '.join(channels)}")
    kind, si_unit, _ = channels[name]
    if isinstance(entry, str):
        entry = {"column": entry}
    if not isinstance(entry, dict):
        raise RecordError(f"{where}: expected a column name or a table {{column = ..., unit = ...}}")
    unknown = sorted(set(entry) - set(_CHANNEL_KEYS))
    if unknown:
        raise RecordError(f"{where}: unknown key {unknown[0]!r}; valid: {', '.join(_CHANNEL_KEYS)}")
    if not isinstance(entry.get("column"), str):
        raise RecordError(f"{where}: missing key 'column' (the column holding channel {name})")
    unit = str(entry.get("unit", si_unit))
    factor = _unit_factor(unit, kind, f"{where}.unit")
    scale = entry.get("scale", 1.0)
    if isinstance(scale, bool) or not isinstance(scale, int | float) or not math.isfinite(scale) or scale == 0:
        raise RecordError(f"{where}: scale = {scale!r}: expected a nonzero number (e.g. -1 for a reversed axis)")
    noise = None
    if "noise" in entry:
        try:
            noise = parse_quantity(entry["noise"], kind, "noise")
        except QuickReleaseError as exc:
            raise RecordError(f"{where}: {exc}") from None
        if not (math.isfinite(noise) and noise > 0):
            raise RecordError(f"{where}: noise = {entry['noise']!r}: expected a positive standard deviation")
    offset = entry.get("offset", name in offsets)
    if not isinstance(offset, bool):
        raise RecordError(f"{where}: offset = {offset!r}: expected true or false")
    drift = entry.get("drift", False)
    if not isinstance(drift, bool):
        raise RecordError(f"{where}: drift = {drift!r}: expected true or false")
    if drift and not drifts:
        raise RecordError(f"{where}: drift = true: a drifting zero is fitted for the building's channels only "
                          "([building.record])")
    file = None
    if "file" in entry:
        if not isinstance(entry["file"], str):
            raise RecordError(f"{where}: file = {entry['file']!r}: expected a path")
        file = Path(entry["file"])
        file = file if file.is_absolute() else base / file
    time_column, time_factor = None, 1.0
    if "time" in entry:
        if file is None:
            raise RecordError(f"{where}: time = {entry['time']!r} without file: a channel in the record's file "
                              "shares its time column (give file = ... for a file with its own time axis)")
        time_column, time_factor = _time_spec(entry["time"], f"{where}.time")
    return ChannelSpec(name=name, column=entry["column"], unit=unit, factor=factor * float(scale), noise=noise,
                       offset=offset, drift=drift, file=file, time_column=time_column, time_factor=time_factor)


# -- the data ------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Channel:
    """One channel's valid samples, SI units (missing samples removed)."""

    spec: ChannelSpec
    t: np.ndarray
    """Sample times [s, record time]."""
    values: np.ndarray
    """Measured values [SI unit of the channel]."""
    index: np.ndarray
    """Row of each sample in the channel's time axis (:attr:`axis`)."""
    missing: int
    """Samples missing (NaN or empty) in this channel, skipped."""
    own_axis: np.ndarray | None = None
    """The channel's own time axis [s] (a file with its own time column and rate); None: the record's."""
    clipped: int = 0
    """Clipped samples left out (:func:`quickrelease.io.timebase.clipped_samples`)."""
    jitter: float = 0.0
    """How far the channel's time stamps scatter about a uniform clock [s]
    (:func:`quickrelease.io.timebase.time_base`)."""

    def axis(self, record_t: np.ndarray) -> np.ndarray:
        """The time axis :attr:`index` refers to: the channel's own, else the record's ``record_t`` [s]."""
        return record_t if self.own_axis is None else self.own_axis

    def sampling_interval(self, record_t: np.ndarray) -> float:
        """Median time step of the channel's time axis [s]."""
        t = self.axis(record_t)
        return float(np.median(np.diff(t))) if t.size > 1 else float("nan")

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def unit(self) -> str:
        return CHANNELS[self.spec.name][1]


@dataclass(frozen=True, eq=False)
class Record:
    """A measured record: a time axis and channels on it (SI)."""

    file: Path
    t: np.ndarray
    """The time axis (rows with a time) [s]."""
    channels: dict[str, Channel]
    dropped_rows: int = 0
    """Rows without a time value, dropped."""
    release_time: float | None = None
    """Start value of the release instant from the case file [s]."""
    notes: list[str] = field(default_factory=list)
    """What was found and done while reading (missing samples, dropped rows)."""

    @property
    def end(self) -> float:
        """Time of the last valid sample of any channel [s]."""
        return max(float(ch.t[-1]) for ch in self.channels.values())

    def sampling_interval(self) -> float:
        """Median time step [s]."""
        return float(np.median(np.diff(self.t))) if self.t.size > 1 else float("nan")


_READERS = {".csv": "read_csv", ".txt": "read_csv", ".tsv": "read_csv", ".parquet": "read_parquet",
            ".feather": "read_feather", ".xlsx": "read_excel", ".xls": "read_excel", ".json": "read_json",
            ".h5": "read_hdf", ".hdf5": "read_hdf"}


def record_files(spec: RecordSpec | None) -> list[Path]:
    """The files a record reads: its own and those of channels with a file of their own."""
    if spec is None:
        return []
    files = [spec.file, *(c.file for c in spec.channels.values() if c.file is not None)]
    return list(dict.fromkeys(files))


def read_table(path: Path):
    """Read a table with pandas, by extension (CSV for anything unknown); RecordError naming the file."""
    import pandas as pd

    from .._files import RECORD_MAX_BYTES, check_input

    reader = _READERS.get(path.suffix.lower(), "read_csv")
    kwargs: dict[str, Any] = {"sep": "\t"} if path.suffix.lower() == ".tsv" else {}
    if not path.exists():
        raise RecordError(f"{path}: record file not found")
    check_input(path, "record file", RecordError, RECORD_MAX_BYTES)  # a device or FIFO would never end
    try:
        return getattr(pd, reader)(path, **kwargs)
    except ImportError as exc:
        raise RecordError(f"{path}: reading {path.suffix} files needs an extra package ({exc})") from None
    except Exception as exc:  # pandas raises many kinds: parser errors, bad files
        reason = (str(exc).splitlines() or [""])[0]
        reason = reason if len(reason) <= 160 else reason[:157] + "..."
        raise RecordError(f"{path}: cannot read the table ({type(exc).__name__}: {_clean_text(reason)})") \
            from None


#: A column name as a header holds it: letters, digits and the marks units are written with, 40 at most.
_HEADER_NAME = re.compile(r"[A-Za-z0-9_ .,()\[\]/^*%+\-]{1,40}")
#: Column names listed in a message, at most.
_LISTED = 8


def _clean_text(text: str) -> str:
    """``text`` with control characters shown as '?' (a message must not carry a file's bytes to a terminal)."""
    return "".join(c if c.isprintable() else "?" for c in text)


def _columns_text(frame) -> str:
    """The columns of ``frame`` for a message: listed (the first eight) only when its first line reads as a
    header of column names; a file's content (a line of another kind of file) is never quoted."""
    names = [c for c in frame.columns]
    if not names or not all(isinstance(c, str) and _HEADER_NAME.fullmatch(c) and not c.startswith("Unnamed:")
                            for c in names):
        return "its first line is not a header of column names"
    shown = ", ".join(names[:_LISTED])
    more = f" and {len(names) - _LISTED} more" if len(names) > _LISTED else ""
    return f"columns: {shown}{more}"


def _cell_text(value: Any) -> str:
    """A cell for a message: short plain text quoted, anything else only described."""
    text = str(value)
    if len(text) <= 24 and _HEADER_NAME.fullmatch(text):
        return repr(text)
    return f"a text of {len(text)} characters"


def _numeric(frame, column: str, path: Path) -> np.ndarray:
    import pandas as pd

    values = pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=float)
    raw = frame[column]
    bad = np.isnan(values) & raw.notna().to_numpy() & (raw.astype(str).str.strip() != "").to_numpy()
    if np.any(bad):
        row = int(np.nonzero(bad)[0][0])
        raise RecordError(f"{path}: column {column!r}: non-numeric value {_cell_text(raw.iloc[row])} at row {row + 1}")
    return values


#: A sample farther from its channel's median than this many times the channel's 1-99 percentile range
#: is a glitch (a dropped bit, an overflowing logger: 1e308 in a displacement), not a measurement. A real
#: record's extremes lie within a few ranges of the median, even a brief release in a long record.
GLITCH_FACTOR = 1e6


def _check_glitches(values: np.ndarray, empty: np.ndarray, rows: np.ndarray, path: Path, column: str,
                    name: str) -> None:
    """Raise RecordError naming file, column, row and value of the first absurd sample: infinite (an
    overflowing number; empty cells are missing samples, not glitches) or :data:`GLITCH_FACTOR` ranges
    away from the median."""
    inf = ~np.isfinite(values) & ~empty
    finite = values[np.isfinite(values)]
    if finite.size >= 3:
        p1, median, p99 = np.percentile(finite, [1.0, 50.0, 99.0])
        scale = max(p99 - p1, abs(median) * 1e-9, np.finfo(float).tiny)
        with np.errstate(over="ignore", invalid="ignore"):
            far = np.isfinite(values) & (np.abs(values - median) > GLITCH_FACTOR * scale)
    else:
        far = np.zeros(values.shape, dtype=bool)
    bad = np.nonzero(inf | far)[0]
    if bad.size:
        i = int(bad[0])
        raise RecordError(f"{path}: column {column!r} (channel {name}): absurd value {values[i]:.6g} at row "
                          f"{int(rows[i]) + 1} ({bad.size} such sample(s); more than {GLITCH_FACTOR:g} times the "
                          "1-99 percentile range from the median, or not finite): correct it or empty the cell "
                          "(an empty cell is a missing sample)")


def _time_axis(frame, column: str, factor: float, path: Path, duplicates: str = "refuse") \
        -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The time column ``column`` of ``frame`` in seconds (rows with a time, repeated stamps once), those
    rows, and the sample each row belongs to; RecordError naming the file and the column when it is
    missing, not numeric, shorter than two values, decreasing, or repeats a stamp with ``duplicates =
    "refuse"``."""
    if column not in frame.columns:
        raise RecordError(f"{path}: no time column {column!r} ({_columns_text(frame)})")
    t = _numeric(frame, column, path) * factor
    rows = np.nonzero(np.isfinite(t))[0]
    if rows.size < 2:
        raise RecordError(f"{path}: column {column!r}: fewer than two time values")
    tt = t[rows]
    steps = np.diff(tt)
    bad = steps < 0 if duplicates == "merge" else steps <= 0
    if np.any(bad):
        k = int(np.nonzero(bad)[0][0])
        hint = (" (a repeated time stamp; duplicates = 'merge' averages the rows of one stamp)" if steps[k] == 0
                else "")
        raise RecordError(f"{path}: column {column!r}: time is not increasing at row {rows[k + 1] + 1} "
                          f"({tt[k + 1]:.6g} s after {tt[k]:.6g} s){hint}")
    group = np.concatenate([[0], np.cumsum(steps > 0)])
    unique = tt[np.concatenate([[True], steps > 0])]
    if unique.size < 2:
        raise RecordError(f"{path}: column {column!r}: fewer than two distinct time values")
    return unique, rows, group


def _note_axis(notes: list[str], file: str, column: str, t: np.ndarray, rows: np.ndarray, groups: np.ndarray) -> None:
    """Notes on a time axis: repeated stamps merged, and stamps that scatter about a uniform clock."""
    repeated = int(rows.size - t.size)
    if repeated:
        shared = int(np.count_nonzero(np.bincount(groups) > 1))
        notes.append(f"{file}: column {column!r}: {repeated + shared} row(s) share {shared} repeated time stamp(s); "
                     "each stamp's rows merged into one sample, their values averaged")
    if t.size >= 3:
        base = time_base(t)
        if base.irregular:
            notes.append(f"{file}: column {column!r}: {base.describe()}")


def _axis_jitter(t: np.ndarray) -> float:
    """The stamps' scatter about a uniform clock [s] where it is worth a note, else 0."""
    if t.size < 3:
        return 0.0
    base = time_base(t)
    return base.jitter if base.irregular else 0.0


def load_record(spec: RecordSpec) -> Record:
    """Read the record a case file points to, as SI channels on the record's time axis (or, for a channel in
    a file with its own time column, on that file's time axis).

    Raises
    ------
    RecordError
        No time column, time not increasing, a column missing or not numeric, a unit of the wrong
        dimension, a channel file of another length (without its own time column), an all-missing
        channel; the message names the file and the column.
    """
    frames: dict[Path, Any] = {}

    def frame_of(path: Path):
        if path not in frames:
            frames[path] = read_table(path)
        return frames[path]

    main = frame_of(spec.file)
    t, rows, groups = _time_axis(main, spec.time_column, spec.time_factor, spec.file, spec.duplicates)
    notes = []
    dropped = int(len(main) - rows.size)
    if dropped:
        notes.append(f"{spec.file.name}: {dropped} row(s) without a time value dropped")
    _note_axis(notes, spec.file.name, spec.time_column, t, rows, groups)
    channels = {}
    own_axes: dict[tuple[Path, str, float], tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
    for name, cs in spec.channels.items():
        path = cs.file or spec.file
        frame = frame_of(path)
        if cs.column not in frame.columns:
            raise RecordError(f"{path}: no column {cs.column!r} for channel {name} ({_columns_text(frame)})")
        axis, axis_rows, axis_groups, own = t, rows, groups, None
        if cs.time_column is not None:  # the channel's own time axis: its file's time column
            key = (path, cs.time_column, cs.time_factor)
            if key not in own_axes:
                own_axes[key] = _time_axis(frame, cs.time_column, cs.time_factor, path, spec.duplicates)
                lost = int(len(frame) - own_axes[key][1].size)
                if lost:
                    notes.append(f"{path.name}: {lost} row(s) without a time value in column {cs.time_column!r} "
                                 "dropped")
                _note_axis(notes, path.name, cs.time_column, *own_axes[key])
            axis, axis_rows, axis_groups = own_axes[key]
            own = axis
        elif cs.file is not None and len(frame) != len(main):
            raise RecordError(f"{path}: column {cs.column!r} has {len(frame)} rows, the time column "
                              f"{spec.time_column!r} of {spec.file.name} has {len(main)} (give the channel's "
                              "own time column: time = ...)")
        rows_ch = axis_rows
        raw = _numeric(frame, cs.column, path)[rows_ch]
        with np.errstate(over="ignore", invalid="ignore"):
            values = raw * cs.factor
        _check_glitches(values, np.isnan(raw), rows_ch, path, cs.column, name)
        if axis.size < values.size:  # repeated time stamps: one sample per stamp, the rows averaged
            values = merge_repeated_times(np.asarray(axis_groups, dtype=float), values)[1][0]
        ok = np.isfinite(values)
        if not np.any(ok):
            raise RecordError(f"{path}: column {cs.column!r} (channel {name}): all values missing")
        missing = int(values.size - ok.sum())
        if missing:
            notes.append(f"{path.name}: column {cs.column!r}: {missing} missing sample(s) skipped (not interpolated)")
        clipped = 0
        if spec.clipped == "exclude":
            clip = clipped_samples(values)
            clipped = int(clip.sum())
            if clipped:
                ok &= ~clip
                levels = ", ".join(f"{v:.6g}" for v in np.unique(values[clip]))
                notes.append(f"{path.name}: column {cs.column!r} (channel {name}): {clipped} clipped sample(s) at "
                             f"{levels} (SI; runs of one value at the channel's extreme, reached at full swing) "
                             "left out")
        idx = np.nonzero(ok)[0]
        jitter = _axis_jitter(axis)
        if jitter > 0.0:
            floor = jitter_misfit(axis[idx], values[idx], jitter)
            against = (f" against the given noise {cs.noise:.3g}: the reduced chi-square of a fit cannot fall below "
                       f"about {1.0 + (floor / cs.noise) ** 2:.3g}") if cs.noise else ""
            notes.append(f"{path.name}: column {cs.column!r} (channel {name}): the time stamps' scatter of "
                         f"{jitter:.3g} s moves its samples by {floor:.3g} rms (jitter |d{name}/dt|){against}")
        _check_noise(cs, values[idx], path, name)
        channels[name] = Channel(spec=cs, t=axis[idx], values=values[idx], index=idx, missing=missing, own_axis=own,
                                 clipped=clipped, jitter=jitter)
    return Record(file=spec.file, t=t, channels=channels, dropped_rows=dropped, release_time=spec.release_time,
                  notes=notes)


#: Smallest noise of a channel relative to its largest value: about 50 ulp of double precision. A smaller
#: noise (e.g. 1e-300 m) would weight residuals that are rounding errors, and overflow the Jacobian (the device's
#: fit, :mod:`quickrelease.studies.fit`, and the building's record, :func:`noise_floor`).
NOISE_FLOOR = 1e-14


def noise_floor(values: np.ndarray) -> float:
    """The smallest noise level a channel of these values may be weighted by [its SI unit]: :data:`NOISE_FLOOR`
    times its largest magnitude, at least 1e-150 (1 / noise^2 stays a float)."""
    return max(NOISE_FLOOR * float(np.max(np.abs(values))), 1e-150)


def _check_noise(cs: ChannelSpec, values: np.ndarray, path: Path, name: str) -> None:
    """RecordError where a channel's given noise standard deviation exceeds its range in the record (largest less
    smallest value): noise of that size would scatter the samples wider than they lie (n samples of noise sigma
    span about 3 sigma at n = 10, 6 sigma at n = 500), so the level is not the sensor's (``noise = "1e308 mm"``
    was fitted, every standard error infinite). A channel of one value is left to the fit's own checks."""
    if cs.noise is None or values.size < 2:
        return
    span = float(np.max(values) - np.min(values))
    if span > 0.0 and not cs.noise <= span:
        unit = abs(cs.factor)
        raise RecordError(f"{path}: column {cs.column!r} (channel {name}): noise = {cs.noise / unit:.6g} {cs.unit}: "
                          f"expected a noise standard deviation in (0, {span / unit:.6g}] {cs.unit}, at most the "
                          "channel's range in the record (its largest less its smallest value)")


def check_release_time(spec: RecordSpec, record: Record) -> None:
    """RecordError where the given release instant lies outside the record's time span (its first to its last
    time stamp, every channel's own axis included): the fit looks for the release near it, and a release
    before the first sample or after the last is nowhere in the record (a building's ``release_time = "-5 s"``
    was fitted, ``"1e308 s"`` ended in a traceback). The device's fit has its own check of a record that starts
    after the fitted release (:func:`quickrelease.studies.fit.fit_record`, naming why)."""
    rt = spec.release_time
    if rt is None:
        return
    axes = [record.t] + [ch.own_axis for ch in record.channels.values() if ch.own_axis is not None]
    lo = min(float(a[0]) for a in axes if a.size)
    hi = max(float(a[-1]) for a in axes if a.size)
    if not lo <= rt <= hi:
        raise RecordError(f"{spec.source}: release_time = {rt:.6g} s: expected a release instant within the time "
                          f"span of the record {spec.file.name}, [{lo:.6g}, {hi:.6g}] s")


def record_origin(record: Record) -> float:
    """The record's first time stamp (of its time axis or of any channel's own) [s, record time]."""
    starts = [float(record.t[0])] + [float(ch.own_axis[0]) for ch in record.channels.values()
                                     if ch.own_axis is not None and ch.own_axis.size]
    return min(starts)


def shifted_record(record: Record, origin: float) -> Record:
    """``record`` on a clock that starts at ``origin`` (every time stamp minus ``origin``): a record stamped
    with Unix time (1.7e9 s) keeps its sample spacing to 1e-16 of the record's length instead of 1e-16 of
    1.7e9 s, and the fit's relative tolerances act on the motion, not on the date."""
    if origin == 0.0:
        return record
    channels = {name: replace(ch, t=ch.t - origin, own_axis=None if ch.own_axis is None else ch.own_axis - origin)
                for name, ch in record.channels.items()}
    return replace(record, t=record.t - origin, channels=channels,
                   release_time=None if record.release_time is None else record.release_time - origin)


def detect_release(record: Record) -> float:
    """A start value of the release instant: where the record first leaves its initial rest [s].

    For each channel: the level and scatter of the first tenth of the record (median, MAD), and the
    first of four consecutive samples more than eight scatters away; for displacement channels the
    departure is extrapolated back to the rest level along the first samples' slope. The earliest
    channel wins.
    """
    best = math.inf
    for ch in record.channels.values():
        n0 = max(10, ch.values.size // 10)
        if ch.values.size < n0 + 5:
            continue
        head = ch.values[:n0]
        level = float(np.median(head))
        spread = 1.4826 * float(np.median(np.abs(head - level)))
        spread = max(spread, 1e-12 * max(1.0, float(np.max(np.abs(ch.values)))))
        away = np.abs(ch.values - level) > 8.0 * spread
        run = away[:-3] & away[1:-2] & away[2:-1] & away[3:]
        hits = np.nonzero(run)[0]
        if not hits.size:
            continue
        i = int(hits[0])
        t_hit = float(ch.t[i])
        if ch.name in DISPLACEMENT_CHANNELS and i + 3 < ch.t.size:
            slope = (ch.values[i + 3] - ch.values[i]) / (ch.t[i + 3] - ch.t[i])
            if slope != 0:
                back = (ch.values[i] - level) / slope
                if 0 <= back <= t_hit - float(ch.t[0]):
                    t_hit -= back
        else:
            t_hit = float(ch.t[max(i - 1, 0)])
        best = min(best, t_hit)
    if not math.isfinite(best):
        raise RecordError(f"{record.file}: no release found: no channel leaves its initial level "
                          "(give [record] release_time)")
    return best

