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
