"""The rcParams guard of tests/conftest.py (issue 22, item 19) and ``plots.save_figure`` called directly.

The guard must catch a change of the user's matplotlib settings made anywhere in a test session: in a test, and in
a module- or session-scoped fixture (set up before a test's own snapshot, so a per-test check alone misses them).
It is run here on planted fixtures in a separate pytest process with a copy of the conftest.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parents[1]  # tests/

_PLANTED = '''
import matplotlib
import pytest


@pytest.fixture(scope="{scope}")
def leaky():
    matplotlib.rcParams["lines.linewidth"] = 7.5  # never restored
    yield


def test_uses_it(leaky):
    pass


def test_after_it():
    pass
'''


@pytest.mark.slow
def test_the_guard_catches_a_leaking_fixture_of_any_scope(tmp_path):
    """One planted module per scope, in one pytest process: each is reported (failed or errored), and a module
    without fixtures is not."""
    shutil.copy(HERE / "conftest.py", tmp_path / "conftest.py")
    for scope in ("function", "module", "session"):
        (tmp_path / f"test_{scope}.py").write_text(_PLANTED.format(scope=scope))
    (tmp_path / "test_clean.py").write_text("def test_nothing():\n    pass\n")
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-rfE", "-p", "no:cacheprovider", "-p", "no:randomly",
                        "-p", "no:xdist", "-p", "no:hypothesispytest", str(tmp_path)],
                       capture_output=True, text=True, cwd=tmp_path, timeout=300)
    out = r.stdout
    assert r.returncode == 1, out[-3000:]
    assert "lines.linewidth" in out, out[-3000:]
    reported = {line.split()[1].split("::")[0].split("/")[-1] for line in out.splitlines() if line.startswith(("FAILED", "ERROR"))}
    assert {"test_function.py", "test_module.py", "test_session.py"} <= reported, out[-3000:]
    assert "test_clean.py" not in reported  # run first (alphabetical order): nothing had leaked yet


def test_save_figure_writes_png_and_svg_at_the_dpi_asked_and_leaves_the_settings(tmp_path):
    """A 4 x 3 inch figure at 50 dpi is 200 x 150 pixels (PNG header, read here); the SVG carries no date (the
    same bytes run to run); no staging file left; the user's rcParams untouched (the autouse guard)."""
    import struct

    from matplotlib.figure import Figure

    from quickrelease.report.plots import save_figure

    fig = Figure(figsize=(4, 3))
    fig.add_subplot().plot([0, 1], [0, 1], label="line")
    paths = save_figure(fig, tmp_path / "sub", "stem", dpi=50)
    assert paths == {"png": tmp_path / "sub" / "stem.png", "svg": tmp_path / "sub" / "stem.svg"}
    png = paths["png"].read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and png[12:16] == b"IHDR"
    assert struct.unpack(">II", png[16:24]) == (200, 150)
    svg = paths["svg"].read_text()
    assert svg.lstrip().startswith("<?xml") and "<dc:date>" not in svg
    again = save_figure(fig, tmp_path / "again", "stem", formats=("svg",), dpi=50)
    assert list(again) == ["svg"] and again["svg"].read_text() == svg
    assert sorted(p.name for p in (tmp_path / "sub").iterdir()) == ["stem.png", "stem.svg"]
