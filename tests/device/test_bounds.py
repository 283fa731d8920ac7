"""Numbers and sizes at the boundary (issue 9, items 8-10): non-finite derived quantities named by the input
that caused them, sizes bounded by the machine before any work, synth validated before it writes."""

from __future__ import annotations

import importlib.util
import math
import shutil
import sys
import tomllib
from importlib import resources
from pathlib import Path

import mpmath
import numpy as np
import pytest

from quickrelease import preset
from quickrelease._validate import available_memory, check_seed, check_size, check_workers
from quickrelease.device.identify import identify_friction
from quickrelease.device.solvers import simulate
from quickrelease.device.statics import internal_forces, strain_energy, strain_energy_limit
from quickrelease.errors import ParameterError, QuickReleaseError
from quickrelease.io.case import load_case
from quickrelease.studies.sweep import parse_grid, sweep
from quickrelease.studies.synth import _toml_value, synthesize
from quickrelease.studies.uq import run_uq

PAPER = Path(str(resources.files("quickrelease") / "data" / "cases" / "paper.toml"))
UQ = Path(str(resources.files("quickrelease") / "data" / "cases" / "uq_paper.toml"))


def _case_with(tmp_path: Path, text: str, source: Path = PAPER) -> Path:
    path = tmp_path / "case.toml"
    path.write_text(source.read_text(encoding="utf-8") + "\n" + text, encoding="utf-8")
    return path


# -- item 8: finite derived quantities ---------------------------------------------------------------

def test_strain_energy_limit_is_where_the_terms_overflow():
    """The largest P, from mpmath's exact squares of Table 3's forces: at the limit every term is finite,
    and a P three times as large overflows a term (so the bound is not set far below where it must be)."""
    d = preset("paper")
    limit = strain_energy_limit(0.2, d)
    assert math.isfinite(strain_energy(limit, 0.2, d).total)
    f = internal_forces(1.0, 0.2, d)
    mpmath.mp.dps = 30
    worst = max(mpmath.mpf(4) * mpmath.mpf(f.N1) ** 2 * d.L1, mpmath.mpf(2) * mpmath.mpf(f.M2) ** 2 * d.L2,
                mpmath.mpf(2) * mpmath.mpf(f.V2) ** 2 * d.L2)
    assert worst * (3 * mpmath.mpf(limit)) ** 2 > sys.float_info.max  # a product of Eq. 2 would overflow
    with pytest.raises(ParameterError, match=r"P = 1e\+300 N is outside \(0, .*\] N"):
        strain_energy(1e300, 0.2, d)


@pytest.mark.parametrize("kwargs,culprit", [
    (dict(stored_energy=2900.0, F1=1e308, F2=0.0), "F1 = 1e+308 N"),
    (dict(stored_energy=2900.0, F1=0.0, F2=1e308), "F2 = 1e+308 N"),
    (dict(stored_energy=5e-324, F1=0.0, F2=0.0), "E_S = 4.94066e-324 J"),
    (dict(stored_energy=2900.0, F1=0.0, F2=0.0, mass_model=1e308), "c = 1e+308"),
])
def test_release_not_resolvable_names_the_input(kwargs, culprit):
    with np.errstate(all="ignore"), pytest.raises(ParameterError) as info:
        simulate(alpha0=0.2, **kwargs)
    assert str(info.value).startswith(culprit), str(info.value)


def test_first_integral_checks_itself():
    """The single-case release every path builds (fit, synth, identify) refuses what it cannot resolve."""
    from quickrelease.device.solvers import FirstIntegral

    d = preset("paper")
    with np.errstate(all="ignore"), pytest.raises(ParameterError, match=r"^F2 = 1e\+308 N"):
        FirstIntegral(2900.0, 0.2, 0.0, 1e308, d.m1, d.m2, d.L1, 2.0 / 3.0)


def test_tiny_energy_gives_finite_times_by_scaling():
    """E_S = 1e-308 J, no friction: t_F scales as 1/sqrt(E_S) exactly (Eq. 10), so it is finite."""
    ref = simulate(2900.0, 0.2, 0.0, 0.0).stop_time
    r = simulate(1e-308, 0.2, 0.0, 0.0)
    assert r.stop_time == pytest.approx(ref * math.sqrt(2900.0) / math.sqrt(1e-308), rel=1e-9)


def test_identify_interval_exact_for_huge_stop_time():
    """t_F = 1e17 s lies far outside the interval; the interval itself is reported exactly (not residual +
    t_F, which rounds to [0, 0])."""
    with pytest.raises(QuickReleaseError) as info:
        identify_friction(0.2, 0.7378, 1e17, stored_energy=2900.0)
    lo, hi = info.value.feasible
    assert 0.5 < lo < hi < 5.0, info.value.feasible


def test_identify_tiny_energy_reports_the_scaled_interval():
    """E_S = 1e-308 J: the feasible stop times are finite and scale as 1/sqrt(E_S) (Eq. 10: the friction
    limits scale with E_S, the rate with its square root); t_F = 1.05 s lies far outside them."""
    with pytest.raises(QuickReleaseError) as ref:
        identify_friction(0.2, 0.7378, 100.0, stored_energy=2900.0)
    with np.errstate(all="ignore"), pytest.raises(QuickReleaseError) as info:
        identify_friction(0.2, 0.7378, 1.05, stored_energy=1e-308)
    scale = math.sqrt(2900.0) / math.sqrt(1e-308)
    np.testing.assert_allclose(info.value.feasible, np.array(ref.value.feasible) * scale, rtol=1e-9)
    with np.errstate(all="ignore"), pytest.raises(ParameterError, match=r"^E_S = 4.94066e-324 J"):
        identify_friction(0.2, 0.7378, 1.05, stored_energy=5e-324)


def test_grid_whose_span_overflows_is_named():
    with pytest.raises(ParameterError, match=r"--grid F1 = -1e\+308:1e\+308 is outside"):
        parse_grid("F1=-1e308:1e308:3")
    with pytest.raises(QuickReleaseError, match="alpha0"):
        parse_grid("alpha0=inf:0.5:3")


# -- item 9: sizes and workers ------------------------------------------------------------------------

def test_check_size_states_the_limit(monkeypatch):
    import quickrelease._validate as validate

    assert available_memory() > 0
    # the memory available changes from one call to the next (other processes): fix it for the check
    monkeypatch.setattr(validate, "available_memory", lambda: 8.0 * 2**30)
    have = 4.0 * 2**30
    check_size("n", 10, int(have // 400))
    with pytest.raises(ParameterError, match=r"4 GiB .*half the memory available now"):
        check_size("n", 10, int(have // 400) + 1)


@pytest.mark.parametrize("workers", [0, -1, 100_000, True, 2.0])
def test_workers_bounded_by_cores(workers):
    with pytest.raises(ParameterError, match="workers"):
        check_workers("workers", workers)


@pytest.mark.parametrize("seed", [-1, 2**63, True])
def test_seed_range(seed):
    with pytest.raises(ParameterError, match="seed"):
        check_seed("seed", seed)


_NO_DASK = pytest.mark.skipif(any(importlib.util.find_spec(m) is None for m in ("dask", "distributed")),
                              reason="the [dask] extra: without it the missing packages are reported first")


@pytest.mark.parametrize("kwargs", [dict(samples=10**23),
                                    pytest.param(dict(samples=400, workers=0, backend="dask"), marks=_NO_DASK),
                                    pytest.param(dict(samples=400, workers=100_000, backend="dask"), marks=_NO_DASK),
                                    dict(samples=400, seed=-1), dict(samples=400, chunk=10**12)])
def test_uq_refuses_before_writing(tmp_path, kwargs):
    out = tmp_path / "run"
    with pytest.raises(ParameterError):
        run_uq(load_case(UQ), out=out, **kwargs)
    assert not out.exists()


@pytest.mark.parametrize("entry", ["[plan]\nsamples = 1000000000000", "n_points = 100000000000"])
def test_case_file_sizes_refused_at_load(tmp_path, entry):
    text = PAPER.read_text(encoding="utf-8")
    if entry.startswith("n_points"):
        text = text.replace("n_points = 1001", entry)
    else:
        text += "\n" + entry + "\n"
    path = tmp_path / "case.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(QuickReleaseError, match="what this machine can hold"):
        load_case(path)


def test_t_end_padding_bounded():
    with pytest.raises(ParameterError, match=r"t_end = 1e\+15 s is outside what this machine can hold"):
        simulate(2900.0, 0.2, 420.0, 800.0, t_end=1e15)


def test_sweep_grid_bounded(tmp_path):
    grids = {"F1": np.zeros(1), "F2": np.zeros(1)}
    with pytest.raises(ParameterError, match="--grid"):
        parse_grid("F1=0 N:1 kN:100000000000000")
    with pytest.raises(ParameterError, match="workers"):
        sweep(load_case(PAPER), grids, workers=0)


def test_explicit_step_bounded_before_stepping():
    with pytest.raises(ParameterError, match=r"dt = 1e-308 s is outside .* = \[5\.\d+e-08, inf\)"):
        simulate(2900.0, 0.2, 420.0, 800.0, method="explicit", dt=1e-308)


# -- item 10: synth validated before anything is written -------------------------------------------------

@pytest.mark.parametrize("kwargs,name", [
    (dict(noise={"u": 0.0}), "noise of u"), (dict(offsets={"u": math.nan}), "offset of u"),
    (dict(rate=1e308), "duration x rate"), (dict(duration=1e308), "duration x rate"),
    (dict(rate=1e-3), "rate"), (dict(seed=-1), "seed"),
])
def test_synth_refuses(kwargs, name):
    args = dict(rate=200.0) | kwargs
    with pytest.raises(ParameterError, match=f"^{name} = "):
        synthesize(load_case(PAPER), ["u"], **args)


def test_synth_cli_writes_nothing_on_bad_noise(tmp_path):
    from typer.testing import CliRunner

    from quickrelease.cli import app

    shutil.copy(PAPER, tmp_path / "case.toml")
    r = CliRunner().invoke(app, ["synth", str(tmp_path / "case.toml"), "--noise", "u=0", "-c", "u",
                                 "--out", str(tmp_path / "r.csv"), "--case-out", str(tmp_path / "fit.toml")])
    assert r.exit_code == 2 and r.stderr.count("\n") == 1, r.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.toml"]


@pytest.mark.parametrize("text", ['a "quoted" name', "C:\\tests\\run", "two\nlines", "tab\tand\x1b[31m",
                                  "Prüfung $x$ ünïcode", "\x7f\x00"])
def test_toml_strings_round_trip(text):
    assert tomllib.loads(f"k = {_toml_value(text)}")["k"] == text


def test_synth_case_out_round_trips(tmp_path):
    """A record file name with a quote, a backslash and a title with a newline: the case file parses."""
    from quickrelease.studies.synth import case_toml

    case = load_case(PAPER).replace(source='lab "B"\\n\nrun')
    syn = synthesize(case, ["u"], rate=200.0)
    text = case_toml(case, syn.record_table('rec "1"\\x.csv'), 'Fit "x"\n')
    data = tomllib.loads(text)
    assert data["record"]["file"] == 'rec "1"\\x.csv' and data["title"] == 'Fit "x"\n'
    assert data["notes"].endswith('lab "B"\\n\nrun')


# -- item 11 (part): the fit refuses noise below the resolution of the record ----------------------------

def test_fit_noise_floor(tmp_path):
    from quickrelease.studies.fit import fit_record

    syn = synthesize(load_case(PAPER), ["u"], rate=200.0, noise={"u": 5e-4})
    syn.write_csv(tmp_path / "r.csv")
    path = _case_with(tmp_path, syn.record_table("r.csv").replace(
        'unit = "m" }', 'unit = "m", noise = "1e-300 m" }'))
    with pytest.raises(QuickReleaseError, match=r"channel u\): noise = 1e-300 \(given\) is below"):
        fit_record(load_case(path))


@pytest.mark.parametrize("column,row,value", [("u_m", 300, "1e308"), ("a_head_m_s2", 400, "1e200"),
                                              ("u_m", 10, "inf"), ("u_m", 20, "1e400")])
def test_fit_names_a_glitched_sample(tmp_path, column, row, value):
    """One absurd sample in a record: file, column and row named, no traceback (the clean record fits)."""
    from quickrelease.studies.fit import fit_record

    syn = synthesize(load_case(PAPER), ["u", "a_head"], rate=200.0)
    syn.write_csv(tmp_path / "r.csv")
    lines = (tmp_path / "r.csv").read_text(encoding="utf-8").splitlines()
    header = lines[0].split(",")
    cells = lines[row].split(",")
    cells[header.index(column)] = value
    lines[row] = ",".join(cells)
    (tmp_path / "g.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    path = _case_with(tmp_path, syn.record_table("g.csv"))
    with pytest.raises(QuickReleaseError, match=rf"g\.csv: column '{column}' .*absurd value .* at row {row} "):
        fit_record(load_case(path))
