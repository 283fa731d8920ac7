"""The console outputs the documentation shows are what today's code prints (issue 22, item 27): each documented
``$ quickrelease ...`` command with an output under it is run as written from a folder laid out as the repository's
root, at 80 columns, and compared with the page. ``python tools/console_outputs.py --write`` regenerates them.

The quick commands (simulate, identify: seconds) run with the tests marked slow (CI); the rest (a run, a fit, a
plan, campaigns, a sweep, a million-sample uq: minutes together) with ``QUICKRELEASE_SLOW=1``.
"""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools"))

import console_outputs  # noqa: E402 - tools/ is not a package

SHOWN = console_outputs.shown_outputs()
QUICK = ("quickrelease simulate", "quickrelease identify")


def test_the_docs_show_console_outputs():
    assert len(SHOWN) >= 10 and sum(s.command.startswith(QUICK) for s in SHOWN) >= 4


@pytest.mark.slow
@pytest.mark.parametrize("shown", SHOWN, ids=[s.where for s in SHOWN])
def test_documented_console_output_is_current(shown):
    if not shown.command.startswith(QUICK) and not os.environ.get("QUICKRELEASE_SLOW"):
        pytest.skip("a slow command: QUICKRELEASE_SLOW=1 runs it")
    folder = console_outputs.root_like_folder()
    try:
        got = console_outputs.run(shown.command, folder)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    assert console_outputs.matches(shown.output, got), console_outputs.diff(shown, got)


def test_the_comparison_reads_excerpts_and_platform_digits():
    m = console_outputs.matches
    assert m("a\n...\nd", "a\nb\nc\nd") and m("a\n...\nd", "a\nd") and m("  ...\nz", "x\ny\nz")
    assert not m("a\n...\nd", "a\nb\nc") and not m("a\nd", "a\nb\nd")
    assert m('"t": 1.0557596493044383', '"t": 1.0557596493044390')  # the 16th digit: the platform's libm
    assert not m('"t": 1.0557596493044383', '"t": 1.0557596493061350')  # the 12th: the code's
    assert not m("F_s 40.138 ± 0.1 kN", "F_s 40.14 ± 0.10 kN")


@pytest.mark.slow
def test_the_check_sees_a_stale_output_and_write_replaces_it(tmp_path, monkeypatch):
    """A page whose shown output is stale: the check reports it (exit 1), --write puts today's output in its place
    and leaves the rest of the page as it was, and the check then passes."""
    page = tmp_path / "page.md"
    page.write_text("# A page\n\n```console\n$ quickrelease --version\nquickrelease 0.0.0-stale\n```\n\nAfter.\n")
    monkeypatch.setattr(console_outputs, "ROOT", tmp_path)
    (tmp_path / "examples").mkdir()
    assert console_outputs.main(["--check", str(page)]) == 1
    assert console_outputs.main(["--write", str(page)]) == 0
    from quickrelease import __version__

    assert page.read_text() == (f"# A page\n\n```console\n$ quickrelease --version\nquickrelease {__version__}\n```\n"
                                "\nAfter.\n")
    assert console_outputs.main(["--check", str(page)]) == 0
