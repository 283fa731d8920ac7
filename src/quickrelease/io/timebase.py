"""The time base and the samples of a real record: repeated stamps, jitter and bursts, clipped samples.

Pure functions on arrays (SI units), called by :func:`quickrelease.io.records.load_record` (which words their
findings as notes) and usable on their own:

- :func:`merge_repeated_times`: rows that share a time stamp become one sample, their values averaged;
- :func:`time_base`: the clock's step and how far the stamps scatter about a uniform clock (random jitter,
  or a logger that stamps its samples in bursts), measured robustly;
- :func:`jitter_misfit`: what that scatter does to a channel, ``jitter |dx/dt|`` (rms), the floor it sets
  under the misfit of any model of the record;
- :func:`clipped_samples`: runs of identical values at a channel's extreme inside the record (a sensor or
  logger at the end of its range), to be left out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError

__all__ = ["TimeBase", "clipped_samples", "jitter_misfit", "merge_repeated_times", "time_base"]

#: Stamps scatter about a uniform clock by more than this fraction of the step before a record says so.
JITTER_NOTE_FRACTION = 0.01
#: A step longer than this many typical steps is a gap in the record (longer than a logger's bursts).
GAP_STEPS = 20.0


def _times(t) -> np.ndarray:
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 2 or not np.all(np.isfinite(t)):
        raise ParameterError("t", f"{t.size} time(s)", "at least two finite times", "s")
    return t


def merge_repeated_times(t, *columns) -> tuple[np.ndarray, list[np.ndarray], np.ndarray]:
    """Rows with the same time stamp as one sample: (unique times [s], each column averaged over its rows,
    the number of rows behind each sample).

    ``t`` must not decrease (equal neighbours are the repeats). A column's missing values (NaN) are left
    out of its average; a sample whose rows are all missing stays NaN. The average of n rows of noise
    sigma has noise sigma / sqrt(n): the counts say which samples are better than the others.
    """
    t = _times(t)
    if np.any(np.diff(t) < 0):
        raise ParameterError("t", "decreasing", "times that never decrease (repeats allowed)", "s")
    start = np.concatenate([[True], np.diff(t) > 0])
    group = np.cumsum(start) - 1
    n = int(group[-1]) + 1
    counts = np.bincount(group, minlength=n)
    merged = []
    for col in columns:
        v = np.asarray(col, dtype=float)
        if v.shape != t.shape:
            raise ParameterError("column", f"{v.size} value(s)", f"{t.size} values, one per time", "")
        ok = np.isfinite(v)
        total = np.bincount(group[ok], weights=v[ok], minlength=n)
        have = np.bincount(group[ok], minlength=n)
        with np.errstate(invalid="ignore", divide="ignore"):
            merged.append(np.where(have > 0, total / np.maximum(have, 1), np.nan))
    return t[start], merged, counts


@dataclass(frozen=True)
class TimeBase:
    """How regular a record's time stamps are (:func:`time_base`), SI units."""

    step: float
    """Typical time step [s]: the median over the record of the time spanned by 16 steps, divided by 16
    (a logger that stamps in bursts makes short and long steps whose median is neither)."""
    jitter: float
    """Robust standard deviation (1.4826 MAD) of the stamps about a uniform clock fitted to each stretch
    between gaps [s]: random jitter, or the sawtooth of burst stamping."""
    step_spread: float
    """Robust standard deviation of the steps about their median, relative to it [-] (sqrt(2) jitter / step
    for independent jitter)."""
    burst_fraction: float
    """Fraction of the steps below half or above one and a half typical steps (gaps aside) [-]."""
    gaps: int
    """Steps longer than GAP_STEPS typical steps (stretches measured apart)."""
    samples: int

    @property
    def irregular(self) -> bool:
        """Whether the stamps scatter by more than :data:`JITTER_NOTE_FRACTION` of the step."""
        return self.jitter > JITTER_NOTE_FRACTION * self.step or self.burst_fraction > 0.05

    def describe(self) -> str:
        """One sentence on the time base, for a note."""
        text = (f"time stamps scatter by {self.jitter:.3g} s (robust standard deviation) about a uniform clock of "
                f"step {self.step:.4g} s")
        if self.burst_fraction > 0.05:
            text += f"; {100 * self.burst_fraction:.0f}% of the steps are under half or over 1.5 steps (burst stamping)"
        if self.gaps:
            text += f"; {self.gaps} gap(s) over {GAP_STEPS:g} steps"
        return text


def time_base(t) -> TimeBase:
    """Measure a record's time base from its stamps t [s] (increasing).

    The record is cut at gaps longer than :data:`GAP_STEPS` typical steps (:attr:`TimeBase.step`); in each
    stretch of at least three samples the stamps are compared with the uniform clock of their least-squares
    line against the sample count, and the jitter is the robust spread (1.4826 MAD) of all the deviations.
    A clock that is merely uneven by design (a slower rate after a gap) is uniform within each stretch; a
    logger that stamps in bursts, or a clock read with jitter, is not.
    """
    t = _times(t)
    steps = np.diff(t)
    if np.any(steps <= 0):
        raise ParameterError("t", "not increasing", "increasing times (merge repeated stamps first)", "s")
    span = min(16, t.size - 1)  # a bursting logger's steps alternate short and long: their span is regular
    step = float(np.median((t[span:] - t[:-span]) / span))
    cuts = np.nonzero(steps > GAP_STEPS * step)[0]
    bounds = np.concatenate([[0], cuts + 1, [t.size]])
    dev = []
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        if b - a >= 3:
            k = np.arange(b - a, dtype=float)
            coef = np.polyfit(k, t[a:b], 1)
            dev.append(t[a:b] - np.polyval(coef, k))
    d = np.concatenate(dev) if dev else np.zeros(1)
    jitter = 1.4826 * float(np.median(np.abs(d - np.median(d))))
    rel = steps / step - 1.0
    spread = 1.4826 * float(np.median(np.abs(rel - np.median(rel))))
    burst = float(np.mean((steps < 0.5 * step) | ((steps > 1.5 * step) & (steps <= GAP_STEPS * step))))
    return TimeBase(step=step, jitter=jitter, step_spread=spread, burst_fraction=burst, gaps=int(cuts.size),
                    samples=int(t.size))


def jitter_misfit(t, x, jitter: float) -> float:
    """RMS of ``jitter |dx/dt|`` over the record [unit of x]: how far stamps that scatter by ``jitter`` [s]
    move the samples from a model evaluated at the stamps. Added in quadrature to the noise, it is a floor
    under the residual of any model: the reduced chi-square cannot fall below about ``1 + (this / noise)^2``.
    dx/dt by central differences on the stamps (one-sided at the ends)."""
    t = _times(t)
    x = np.asarray(x, dtype=float)
    if x.shape != t.shape:
        raise ParameterError("x", f"{x.size} value(s)", f"{t.size} values, one per time", "")
    if not (math.isfinite(jitter) and jitter >= 0):
        raise ParameterError("jitter", jitter, "[0, inf)", "s")
    ok = np.isfinite(x)
    if np.count_nonzero(ok) < 3:
        return 0.0
    rate = np.gradient(x[ok], t[ok])
    return float(jitter * math.sqrt(float(np.mean(rate**2))))


def clipped_samples(x, min_run: int = 3) -> np.ndarray:
    """Mask of the clipped samples of a channel x: runs of at least ``min_run`` identical values at the
    channel's largest or smallest value, inside the record (not touching its first or last sample: a
    record that starts or ends at rest is not clipped), entered and left by steps of at least four
    quanta (the smallest nonzero difference between the channel's values: a smooth peak of a quantised
    channel also repeats its top value, but reaches it by steps of about one quantum, while a sensor at
    the end of its range is hit by the swing at full speed). Missing values (NaN) are never clipped."""
    x = np.asarray(x, dtype=float)
    mask = np.zeros(x.shape, dtype=bool)
    ok = np.isfinite(x)
    if np.count_nonzero(ok) < min_run + 2:
        return mask
    idx = np.nonzero(ok)[0]
    v = x[idx]
    diffs = np.abs(np.diff(np.unique(v)))
    quantum = float(np.min(diffs)) if diffs.size else 0.0
    for level in (float(np.max(v)), float(np.min(v))):
        at = v == level
        edges = np.diff(np.concatenate([[0], at.astype(int), [0]]))
        starts, ends = np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0]  # run [s, e)
        for s, e in zip(starts, ends, strict=True):
            if e - s < min_run or s < 2 or e > v.size - 2:
                continue
            step_in = abs(v[s - 1] - v[s - 2])
            step_out = abs(v[e + 1] - v[e]) if e + 1 < v.size else 0.0
            entering = abs(v[s] - v[s - 1])
            leaving = abs(v[e] - v[e - 1])
            if min(max(step_in, entering), max(step_out, leaving)) >= 4.0 * quantum:
                mask[idx[s:e]] = True
    return mask
