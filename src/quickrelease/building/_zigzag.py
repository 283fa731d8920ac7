"""The zigzag with hysteresis: the turning points of a noisy sampled displacement, each a running extreme from which
the record has come back by more than a threshold. One scan for the cycles of a loop
(:func:`quickrelease.building.effective.cycle_turns`) and the turning points of a decay
(:func:`quickrelease.building.decay.turning_points`), so that neither module imports the other for it."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["zigzag", "zigzag_scan"]


def zigzag(x: np.ndarray, threshold: float) -> np.ndarray:
    """The samples of the running extremes from which x came back by more than ``threshold``, in time order
    (the first direction: the first move beyond the threshold from the first sample; the first sample itself
    is no turning point, e.g. a release from rest: give it in ``turns``)."""
    k0 = np.nonzero(np.abs(x - x[0]) > threshold)[0] if x.size else np.array([], dtype=int)
    if k0.size == 0:
        return np.array([], dtype=int)
    direction = 1.0 if x[k0[0]] > x[0] else -1.0
    out, _, _ = zigzag_scan(x, threshold, direction, int(k0[0]))
    return np.array(out, dtype=int)


def zigzag_scan(x: np.ndarray, threshold: float, direction: float, best: int) -> tuple[list[int], float, int]:
    """The zigzag with hysteresis from sample ``best`` on, moving in ``direction`` (+1 up, -1 down): the running
    extreme in the current direction becomes a turning point once x has come back from it by more than
    ``threshold`` [x's unit]. Returns the turning points' samples, and the direction and running extreme at
    the end (the last swing's, not yet a turning point). Shared by
    :func:`quickrelease.building.effective.cycle_turns` and :func:`quickrelease.building.decay.turning_points`."""
    x = np.asarray(x, dtype=float)
    if direction not in (1.0, -1.0) or not threshold >= 0.0 or not math.isfinite(threshold) \
            or not np.all(np.isfinite(x[best:])):
        return _scan_loop(x, threshold, direction, best)
    out: list[int] = []
    # per swing, one pass of numpy over the rest of the record: y = direction x (exact), the running extreme so far,
    # the first sample that came back from it by more than the threshold (a sample that equals the extreme is no new
    # extreme: the first of equal extremes is the turning point, as in the sample-by-sample scan of _scan_loop)
    while best + 1 < x.size:
        span = 256  # a window that grows until the swing turns: each pass over the samples of its swing (and as
        while True:  # many again at most), not over the rest of the record (quadratic in a chattering record)
            end = min(x.size, best + span)
            y = direction * x[best:end]
            peak = np.maximum.accumulate(y)
            back = np.nonzero(peak[:-1] - y[1:] > threshold)[0]
            if back.size or end == x.size:
                break
            span *= 4
        if back.size == 0:
            best += int(np.argmax(y))
            break
        k = int(back[0]) + 1  # the sample (from best) that turns the swing
        out.append(best + int(np.argmax(y[:k])))
        direction = -direction
        best += k
    return out, direction, best


def _scan_loop(x: np.ndarray, threshold: float, direction: float, best: int) -> tuple[list[int], float, int]:
    """:func:`zigzag_scan` sample by sample (for records with NaN or inf, and any threshold)."""
    out: list[int] = []
    for k in range(best + 1, x.size):
        if direction * (x[k] - x[best]) > 0.0:
            best = k
        elif direction * (x[best] - x[k]) > threshold:
            out.append(best)
            direction = -direction
            best = k
    return out, direction, best
