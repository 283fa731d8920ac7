"""Uncertainty: reproducibility, resume, sensitivities, case-file scatter."""

import importlib.util
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from quickrelease import identify_friction
from quickrelease.case import CaseFileError, load_case
from quickrelease.errors import QuickReleaseError
from quickrelease.uq import run_uq, sensitivities

CASE = """
title = "uq"
[test]
force = { value = "1598 kN", std = "16 kN" }
alpha0 = { value = "0.2 rad", std = "0.005 rad" }
[observations]
alpha_final = { value = "0.7378 rad", std = "0.01 rad" }
stop_time = { low = "1.04 s", high = "1.06 s" }
"""
HAS_DASK = importlib.util.find_spec("dask") is not None and importlib.util.find_spec("distributed") is not None


@pytest.fixture()
def case_path(tmp_path):
    path = tmp_path / "uq.toml"
    path.write_text(CASE)
    return path


def test_distributions_parsed(case_path):
    case = load_case(case_path)
    assert case.uncertainty["alpha_final"].kind == "normal" and case.uncertainty["alpha_final"].scale == 0.01
    assert case.uncertainty["stop_time"].kind == "uniform" and case.stop_time == pytest.approx(1.05)
    assert case.uncertainty["force"].loc == 1598e3 and case.push_force == 1598e3


@pytest.mark.parametrize("entry,message", [
    ('alpha_final = { value = "0.7378 rad", sigma = "0.01 rad" }', r"unknown key 'sigma' in \[observations\] alpha_final"),
    ('alpha_final = { value = "0.7378 rad", std = "0.01 m" }', r"\[observations\] alpha_final.std: .*expected an angle"),
    ('alpha_final = { value = "0.7378 rad" }', r"give value and std \(normal\) or low and high \(uniform\)"),
    ('alpha_final = { low = "0.8 rad", high = "0.7 rad" }', r"alpha_final.high = '0.7 rad': expected a value above"),
    ('alpha_final = { value = "0.7378 rad", std = "-0.01 rad" }', r"alpha_final.std = '-0.01 rad': expected a standard"),
])
def test_scatter_errors(tmp_path, entry, message):
    path = tmp_path / "c.toml"
    path.write_text(CASE.replace('alpha_final = { value = "0.7378 rad", std = "0.01 rad" }', entry))
    with pytest.raises(CaseFileError, match=message):
        load_case(path)


def test_force_scatter_with_given_energy_is_refused(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text(CASE.replace("[test]\n", '[test]\nenergy = "2.9 kJ"\n'))
    with pytest.raises(QuickReleaseError, match="force has a scatter but energy is given"):
        run_uq(load_case(path), 100)


def test_reproducible_and_chunk_independent_of_backend_order(case_path):
    case = load_case(case_path)
    a = run_uq(case, 60_000, seed=3, chunk=20_000)
    b = run_uq(case, 60_000, seed=3, chunk=20_000)
    assert a.summary() == b.summary()
    c = run_uq(case, 60_000, seed=4, chunk=20_000)
    assert c.percentiles != a.percentiles
    # nominal point and plausible spread
    nominal = identify_friction(0.2, 0.7378, 1.05, push_force=1598e3)
    assert a.nominal["F1"] == pytest.approx(nominal.F1, rel=1e-10)
    assert a.percentiles["F1"]["p2.5"] < nominal.F1 < a.percentiles["F1"]["p97.5"]
    assert -1.0 < a.correlation < -0.95  # on the line of Eq. 13 F1 and F2 trade off
    assert 0.0 < a.infeasible_share < 0.05
    assert sum(a.status_counts.values()) == 60_000


def test_percentiles_match_exact_ones(case_path):
    """The histogram percentiles agree with numpy's exact ones within the bin width."""
    from quickrelease import uq

    case = load_case(case_path)
    r = run_uq(case, 40_000, seed=1, chunk=40_000)
    rng = np.random.default_rng(np.random.SeedSequence([1, 0]))
    ident = uq._identify(case, uq._inputs(case, rng, 40_000))
    ok = ident.status == 0
    exact = np.percentile(ident.F1[ok], [2.5, 50, 97.5])
    got = [r.percentiles["F1"][k] for k in ("p2.5", "p50", "p97.5")]
    np.testing.assert_allclose(got, exact, atol=2 * r.resolution["F1"])
    assert r.mean["F1"] == pytest.approx(ident.F1[ok].mean(), rel=1e-12)
    assert r.correlation == pytest.approx(np.corrcoef(ident.F1[ok], ident.F2[ok])[0, 1], rel=1e-10)


def test_sensitivities_ift_match_finite_differences(case_path):
    ift, fd = sensitivities(load_case(case_path))
    for f in ("F1", "F2"):
        for x in ("alpha0", "alpha_final", "stop_time", "force"):
            assert ift[f][x] == pytest.approx(fd[f][x], rel=1e-6), (f, x)
    # signs: a later stop means more hinge friction (F1 up, F2 down)
    assert ift["F1"]["stop_time"] > 0 > ift["F2"]["stop_time"]


def _uq_cmd(case_path, out, backend, samples=2_000_000, chunk=50_000):
    return [sys.executable, "-m", "quickrelease.cli", "uq", str(case_path), "--samples", str(samples), "--chunk",
            str(chunk), "--seed", "7", "--backend", backend, "--out", str(out), "--json"]


@pytest.mark.parametrize("backend", ["numpy", pytest.param("dask", marks=pytest.mark.skipif(
    not HAS_DASK, reason="dask not installed"))])
def test_interrupted_run_resumes_to_the_same_file(case_path, tmp_path, backend):
    full = tmp_path / "full"
    subprocess.run(_uq_cmd(case_path, full, backend), check=True, capture_output=True, timeout=600)
    part = tmp_path / "part"
    proc = subprocess.Popen(_uq_cmd(case_path, part, backend), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    staging = tmp_path / ".part.partial"  # the run works beside --out and moves into place when complete
    deadline = time.time() + 300
    while time.time() < deadline and len(list((staging / "chunks").glob("chunk-*.npz"))) < 8:
        time.sleep(0.05)
    import os

    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    finished = len(list((staging / "chunks").glob("chunk-*.npz")))
    assert 8 <= finished < 40, finished
    assert not part.exists()  # nothing that looks like a result
    # without --resume the folder is refused; with it the run completes
    again = subprocess.run(_uq_cmd(case_path, part, backend), capture_output=True, text=True, timeout=600)
    assert again.returncode == 2 and "pass --resume" in again.stderr
    subprocess.run(_uq_cmd(case_path, part, backend) + ["--resume"], check=True, capture_output=True, timeout=600)
    assert (part / "uq.json").read_bytes() == (full / "uq.json").read_bytes()
    assert json.loads((full / "uq.json").read_text())["samples"] == 2_000_000


@pytest.mark.skipif(not HAS_DASK, reason="dask not installed")
def test_dask_and_numpy_backends_agree_exactly(case_path, tmp_path):
    a = run_uq(load_case(case_path), 100_000, seed=2, chunk=25_000, out=tmp_path / "a")
    b = run_uq(load_case(case_path), 100_000, seed=2, chunk=25_000, out=tmp_path / "b", backend="dask")
    assert (tmp_path / "a" / "uq.json").read_bytes() == (tmp_path / "b" / "uq.json").read_bytes()
    assert a.percentiles == b.percentiles


def test_uq_cli_writes_the_corner_figure(case_path, tmp_path):
    from typer.testing import CliRunner

    from quickrelease.cli import app

    r = CliRunner().invoke(app, ["uq", str(case_path), "--samples", "20000", "--out", str(tmp_path / "o")])
    assert r.exit_code == 0, r.output
    assert "dF1/dstop_time" in r.stdout and "97.5%" in r.stdout
    assert (tmp_path / "o" / "uq_corner.png").stat().st_size > 20_000
    assert Path(tmp_path / "o" / "uq.json").exists()
