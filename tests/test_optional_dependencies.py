"""Optional dependencies are checked once, before any work (issue 11): a command that needs zarr, dask or
pyarrow and lacks it prints one line naming the package and how to install it, exits 2, and writes nothing.

``sweep --out x.zarr`` without zarr: tests/cli/test_cli_conventions.py. A package is hidden the way Python sees
a missing one: ``sys.modules[name] = None`` makes ``find_spec`` and
``import`` both fail."""

import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from quickrelease import QuickReleaseError
from quickrelease.cli import app
from quickrelease.studies.distributed import check_optional

EXAMPLES = Path(__file__).parent.parent / "examples"
runner = CliRunner()


def hide(monkeypatch, *names):
    for name in names:
        monkeypatch.setitem(sys.modules, name, None)


def one_line_exit_2(r, *words):
    assert r.exit_code == 2, r.output
    assert "Traceback" not in r.output and r.stderr.count("\n") == 1, r.output
    for word in words:
        assert word in r.stderr, (word, r.stderr)


@pytest.mark.parametrize("command", ["uq", "sweep"])
def test_dask_backend_without_dask(monkeypatch, tmp_path, command):
    hide(monkeypatch, "distributed")
    args = (["uq", str(EXAMPLES / "uq_paper.toml"), "--out", str(tmp_path / "o")] if command == "uq" else
            ["sweep", str(EXAMPLES / "larger_push.toml"), "--grid", "alpha0=0.1:0.5:3", "--out",
             str(tmp_path / "s.zarr")])
    r = runner.invoke(app, [*args, "--backend", "dask"])
    one_line_exit_2(r, "the dask backend needs ", "distributed", "pip install 'quickrelease[dask]'")  # and dask, if
    # it is missing too (an install without the dask extra)
    assert list(tmp_path.iterdir()) == []  # no output folder half made


def _parquet_case(tmp_path, source: Path) -> Path:
    """``source`` with its record file named .parquet (the file need not exist: the check comes first)."""
    text = source.read_text(encoding="utf-8").replace('records/', str(source.parent / "records") + "/")
    text = text.replace("paper_500Hz.csv", "paper_500Hz.parquet").replace("building_200Hz.csv",
                                                                            "building_200Hz.parquet")
    path = tmp_path / source.name
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize(("command", "source", "record"), [
    ("fit", "fit.toml", "paper_500Hz.parquet"),
    ("run", "fit.toml", "paper_500Hz.parquet"),
    ("building", "building.toml", "building_200Hz.parquet"),
])
def test_parquet_records_without_pyarrow(monkeypatch, tmp_path, command, source, record):
    hide(monkeypatch, "pyarrow")
    case = _parquet_case(tmp_path, EXAMPLES / source)
    r = runner.invoke(app, [command, str(case), "--out", str(tmp_path / "o")])
    one_line_exit_2(r, record, "needs pyarrow")
    assert not (tmp_path / "o").exists()


def test_campaign_checks_every_test_before_the_first_fit(monkeypatch, tmp_path):
    hide(monkeypatch, "pyarrow")
    text = (EXAMPLES / "campaign.toml").read_text(encoding="utf-8")
    last = text.rindex("campaign_T")  # the last test's record only: found before T1 is fitted
    text = text[:last] + text[last:].replace(".csv", ".parquet", 1)
    (tmp_path / "records").symlink_to(EXAMPLES / "records")
    path = tmp_path / "campaign.toml"
    path.write_text(text, encoding="utf-8")
    import quickrelease.studies.campaign as campaign

    monkeypatch.setattr(campaign, "_identify_test", lambda *a: pytest.fail("a test was fitted before the check"))
    r = runner.invoke(app, ["campaign", str(path)])
    one_line_exit_2(r, ".parquet", "needs pyarrow")


def test_check_optional_passes_what_is_installed_and_ignores_other_suffixes():
    check_optional(backend="numpy", files=["a.csv", "b.nc", "c.txt"])
    pytest.importorskip("zarr")
    check_optional(files=["x.zarr"])


def test_a_broken_package_counts_as_missing(monkeypatch):
    import importlib.util

    def broken(name, *a):
        raise ValueError(f"{name}.__spec__ is None")

    monkeypatch.setattr(importlib.util, "find_spec", broken)
    with pytest.raises(QuickReleaseError, match=r"^x\.feather needs pyarrow \(not installed\)"):
        check_optional(files=["x.feather"])
