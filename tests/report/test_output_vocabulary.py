"""One output vocabulary (issue 22, item 26): --out on every command (a folder, or the one file a command
writes), its default stated in the help, ``report --json``, the demo's JSON keys with unit suffixes, and
"Wrote N files" counting the files that are there."""

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from quickrelease.cli import app

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
runner = CliRunner()
WIDE = {"COLUMNS": "250"}


def _files(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file())


@pytest.mark.parametrize("command, default", [
    ("run", "[default: quickrelease-out]"), ("report", "[default: quickrelease-out]"),
    ("demo", "[default: quickrelease-demo]"), ("sweep", "[default: sweep.nc]"), ("synth", "[default: record.csv]"),
    ("uq", "(default: none, nothing written)"), ("fit", "(default: none, print only)"),
    ("building", "(default: none, print only)"), ("campaign", "(default: none, print only)"),
    ("plan", "(default: none, print only)"), ("simulate", "(default: none, print only)"),
    ("identify", "(default: none, print only)"), ("bench", "(default: none, print only)"),
])
def test_out_and_its_default_in_every_help(command, default):
    r = runner.invoke(app, [command, "--help"], env=WIDE)
    assert r.exit_code == 0
    line = " ".join(r.output.split())  # rich wraps the help; the words, not the layout
    assert "--out" in line and default in line, command


@pytest.mark.slow
def test_report_json_lists_what_it_wrote(tmp_path):
    out = tmp_path / "r"
    r = runner.invoke(app, ["report", str(EXAMPLES / "paper.toml"), "--out", str(out), "--json"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    assert data["report"] == str(out / "report.html")
    assert sorted(data["files"]) == sorted(str(out / f) for f in _files(out)) == \
        [str(out / "manifest.json"), str(out / "report.html")]
    r = runner.invoke(app, ["report", str(EXAMPLES / "paper.toml"), "--out", str(tmp_path / "r2")])
    assert r.exit_code == 0 and r.stdout.startswith(f"Wrote 2 files to {tmp_path / 'r2'}/: report.html")


@pytest.mark.slow
def test_run_counts_every_file_it_wrote(tmp_path):
    out = tmp_path / "run"
    r = runner.invoke(app, ["run", str(EXAMPLES / "paper.toml"), "--out", str(out)])
    assert r.exit_code == 0, r.output
    on_disk = _files(out)
    assert "manifest.json" in on_disk
    assert f"Wrote {len(on_disk)} files to {out}/:" in r.stdout
    listed = sorted(line.strip() for line in r.stdout.splitlines() if line.startswith("  "))
    assert listed == on_disk
    r = runner.invoke(app, ["run", str(EXAMPLES / "paper.toml"), "--out", str(tmp_path / "j"), "--json"])
    files = json.loads(r.stdout)["files"]
    assert sorted(Path(p).name for p in files.values()) == sorted(Path(p).name for p in _files(tmp_path / "j"))


#: The demo's JSON keys, written by hand: each with its SI unit, as every other command's (issue 22, item 26).
DEMO_KEYS = [
    "device", "mass_model", "printed_P_N", "printed_alpha0_rad", "printed_alpha_final_rad", "printed_E_S_J",
    "printed_t_F_s", "printed_F1_N", "printed_F2_N", "E_S_eq2_J", "E_S_breakdown_J", "P_for_printed_E_S_N",
    "F1_printed_inputs_N", "F2_printed_inputs_N", "F1_max_N", "F2_max_N", "F1_eq2_N", "F2_eq2_N", "F1_range_t_F_N",
    "F1_range_all_N", "F2_range_all_N", "t_F_for_paper_F1_s", "E_S_implied_by_paper_pair_J", "line_sum_paper_pair",
    "paper_pair_alpha_final_rad", "paper_pair_stop_time_s", "paper_pair_stop_time_on_line_s",
    "lumped_feasible_stop_time_s", "feasible_stop_time_s", "mass_factor", "peak_u_dot_m_s", "peak_v_dot_m_s",
    "u_final_m", "v_final_m", "alpha_dot0_rad_s", "table7", "out", "files",
]


@pytest.mark.slow
def test_demo_json_keys_carry_their_units(tmp_path):
    out = tmp_path / "demo"
    r = runner.invoke(app, ["demo", "--out", str(out), "--json"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    assert list(data) == DEMO_KEYS
    assert data["printed_F1_N"] == 405.6 and data["printed_t_F_s"] == 1.05  # Table 7 as printed, SI
    assert data["E_S_eq2_J"] == pytest.approx(2915.419, abs=1e-3)
    assert sorted(data["files"]) == sorted(str(out / f) for f in _files(out))
    table7 = json.loads((out / "table7.json").read_text(encoding="utf-8"))
    assert [k for k in table7 if k != "provenance"] == DEMO_KEYS[2:-2]


def test_simulate_and_identify_write_one_file(tmp_path):
    import xarray as xr

    from quickrelease.io.export import read_csv

    base = ["simulate", "--energy", "2900", "--alpha0", "0.2", "--f1", "420", "--f2", "800"]
    r = runner.invoke(app, [*base, "--out", str(tmp_path / "s.csv")])
    assert r.exit_code == 0 and r.stdout.rstrip().endswith(f"Wrote 1 file: {tmp_path / 's.csv'}")
    columns = read_csv(tmp_path / "s.csv")
    assert list(columns)[:3] == ["t_s", "alpha_rad", "alpha_dot_rad_s"] and columns["alpha_rad"][0] == 0.2
    r = runner.invoke(app, [*base, "--out", str(tmp_path / "s.nc"), "--json"])
    assert json.loads(r.stdout)["files"] == [str(tmp_path / "s.nc")]
    with xr.open_dataset(tmp_path / "s.nc") as ds:
        assert ds["alpha"].attrs["units"] == "rad"
    r = runner.invoke(app, [*base, "--out", str(tmp_path / "s.json")])
    assert json.loads((tmp_path / "s.json").read_text())["stop_time_s"] > 0
    # an existing file is kept unless --overwrite; a suffix the command does not write is refused
    before = (tmp_path / "s.csv").read_bytes()
    r = runner.invoke(app, [*base, "--out", str(tmp_path / "s.csv")])
    assert r.exit_code == 2 and "already there; give --overwrite" in r.stderr and r.stderr.count("\n") == 1
    assert (tmp_path / "s.csv").read_bytes() == before
    assert runner.invoke(app, [*base, "--out", str(tmp_path / "s.csv"), "--overwrite"]).exit_code == 0
    r = runner.invoke(app, [*base, "--out", str(tmp_path / "s.txt")])
    assert r.exit_code == 2 and "expected a file name ending in .csv or .nc or .json" in r.stderr
    assert not (tmp_path / "s.txt").exists()
    r = runner.invoke(app, ["identify", "--energy", "2900", "--alpha0", "0.2", "--alpha-final", "0.7378",
                            "--stop-time", "1.05", "--out", str(tmp_path / "i.json")])
    assert r.exit_code == 0
    assert json.loads((tmp_path / "i.json").read_text())["F1_N"] == pytest.approx(419.85, abs=0.01)


def test_bench_out_is_checked_before_the_work(tmp_path, monkeypatch):
    import quickrelease.studies.bench as bench

    monkeypatch.setattr(bench, "run_bench", lambda **kw: pytest.fail("the bench started before the check"))
    r = runner.invoke(app, ["bench", "--quick", "--out", str(tmp_path / "b.csv")])
    assert r.exit_code == 2 and "ending in .json" in r.stderr
    monkeypatch.setattr(bench, "run_bench", lambda **kw: {"quick": True})
    monkeypatch.setattr("quickrelease.cli._bench_tables", lambda result: None)
    r = runner.invoke(app, ["bench", "--quick", "--out", str(tmp_path / "b.json")])
    assert r.exit_code == 0 and json.loads((tmp_path / "b.json").read_text()) == {"quick": True}
