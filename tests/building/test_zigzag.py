"""The zigzag with hysteresis (quickrelease.building._zigzag), shared by the loop's cycles (building.effective) and
the decay's turning points (building.decay), against turning points read by eye off sequences written here."""

import ast
from pathlib import Path

import numpy as np
import pytest

from quickrelease.building import decay, effective
from quickrelease.building._zigzag import zigzag, zigzag_scan

SRC = Path(decay.__file__).resolve().parent


@pytest.mark.parametrize("x, threshold, turns", [
    ([0, 1, 3, 2.5, 3.2, 1, 0, -2, -1.5, -2.2, 0, 1], 1.0, [4, 9]),  # wiggles of 0.5-0.7 inside the threshold
    ([0, 1, 3, 2.5, 3.2, 1, 0, -2, -1.5, -2.2, 0, 1], 0.4, [2, 3, 4, 7, 8, 9]),  # the same wiggles beyond 0.4
    ([0, 0.1, -0.1, 0.05], 0.5, []),  # never beyond the threshold: no turning point
    ([5, 4, 2, 3, 4, 3.5, 1], 0.5, [2, 4]),  # going down first
    ([], 1.0, []),
    ([0, 2, 1, 3], 1.0, []),  # back by exactly the threshold: not beyond it
])
def test_the_zigzag_finds_the_extremes_it_came_back_from(x, threshold, turns):
    assert zigzag(np.asarray(x, dtype=float), threshold).tolist() == turns


def test_the_scan_returns_the_last_swing_not_yet_a_turning_point():
    out, direction, best = zigzag_scan(np.array([0.0, 2.0, 0.5, 3.0, 2.9]), 1.0, 1.0, 0)
    assert (out, direction, best) == ([1, 2], 1.0, 3)


def test_the_scan_is_the_one_effective_and_decay_use_and_decay_does_not_import_effective():
    """building.effective re-exports the scan (its home before); building.decay takes it from building._zigzag,
    not from building.effective (which it imported for it alone)."""
    assert effective.zigzag_scan is zigzag_scan and decay.zigzag_scan is zigzag_scan
    tree = ast.parse((SRC / "decay.py").read_text(encoding="utf-8"))
    imported = {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
    assert "effective" not in imported and "_zigzag" in imported


def _scan_by_hand(x, threshold, direction, best):
    """The scan sample by sample, written here: a strictly larger sample (in ``direction``) is the new extreme, a
    sample back from the extreme by more than the threshold turns the swing."""
    out = []
    for k in range(best + 1, len(x)):
        if direction * (x[k] - x[best]) > 0.0:
            best = k
        elif direction * (x[best] - x[k]) > threshold:
            out.append(best)
            direction, best = -direction, k
    return out, direction, best


def test_the_scan_is_the_sample_by_sample_scan_on_noisy_quantised_and_flat_records():
    """The scan (one numpy pass per swing) against the loop above on 3000 drawn records: decays with noise, the
    same quantised (equal samples: the first of equal extremes is the turning point), integer steps, -0.0 among
    0.0, samples of +-1e308 (differences overflow to inf), NaN and inf, thresholds 0 and negative."""
    rng = np.random.default_rng(7)
    for trial in range(3000):
        n = int(rng.integers(0, 120))
        t = np.linspace(0.0, rng.uniform(1.0, 30.0), n)
        x = rng.uniform(0.01, 1.0) * np.exp(-0.1 * t) * np.cos(rng.uniform(0.5, 5.0) * t) + rng.normal(0.0, 0.05, n)
        kind = trial % 6
        if kind == 1:
            x = np.round(x * 100.0) / 100.0
        elif kind == 2:
            x = rng.integers(-3, 4, n).astype(float)
        elif kind == 3 and n:
            x[rng.integers(0, n, 3)] = rng.choice([np.nan, np.inf, -np.inf, 1e308, -1e308])
        elif kind == 4:
            x = np.where(rng.uniform(size=n) < 0.3, -0.0, np.round(x))
        threshold = float(rng.choice([0.0, 0.02, 0.3, -0.1]))
        direction, best = float(rng.choice([1.0, -1.0])), int(rng.integers(0, max(n, 1)))
        with np.errstate(invalid="ignore", over="ignore"):
            assert zigzag_scan(x, threshold, direction, best) == _scan_by_hand(x, threshold, direction, best), trial
