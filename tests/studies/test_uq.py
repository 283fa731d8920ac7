"""Uncertainty: reproducibility, resume, sensitivities, case-file scatter."""

import importlib.util
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import UQ_CASE

from quickrelease import identify_friction
from quickrelease.errors import QuickReleaseError
from quickrelease.io.case import CaseFileError, load_case
from quickrelease.studies.uq import run_uq, sensitivities

HAS_DASK = importlib.util.find_spec("dask") is not None and importlib.util.find_spec("distributed") is not None


@pytest.fixture()
def case_path(tmp_path):
    path = tmp_path / "uq.toml"
    path.write_text(UQ_CASE)
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
    path.write_text(UQ_CASE.replace('alpha_final = { value = "0.7378 rad", std = "0.01 rad" }', entry))
    with pytest.raises(CaseFileError, match=message):
        load_case(path)


def test_force_scatter_with_given_energy_is_refused(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text(UQ_CASE.replace("[test]\n", '[test]\nenergy = "2.9 kJ"\n'))
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
    from quickrelease.studies import uq

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


def test_chunked_moments_match_one_shot_numpy(case_path):
    """Four chunks combined (Chan et al.: within-chunk comoments plus the between-chunk term) give the mean,
    std and correlation numpy computes in one shot on the same 40,000 samples (chunk j draws from
    SeedSequence([seed, j])). Without the between-chunk term the variance is short by the spread of the chunk
    means, ~1e-4 relative here."""
    from quickrelease.studies import uq

    case = load_case(case_path)
    r = run_uq(case, 40_000, seed=5, chunk=10_000)
    parts = [uq._identify(case, uq._inputs(case, np.random.default_rng(np.random.SeedSequence([5, j])), 10_000))
             for j in range(4)]
    ok = np.concatenate([p.status == 0 for p in parts])
    F1, F2 = np.concatenate([p.F1 for p in parts])[ok], np.concatenate([p.F2 for p in parts])[ok]
    assert sum(r.status_counts.values()) == 40_000 and r.status_counts["ok"] == int(ok.sum())
    for name, x in (("F1", F1), ("F2", F2)):
        assert r.mean[name] == pytest.approx(float(np.mean(x)), rel=1e-12)
        assert r.std[name] == pytest.approx(float(np.std(x, ddof=1)), rel=1e-10)
    assert r.correlation == pytest.approx(float(np.corrcoef(F1, F2)[0, 1]), rel=1e-10)


def _uq_cmd(case_path, out, backend, samples=2_000_000, chunk=50_000):
    return [sys.executable, "-m", "quickrelease.cli", "uq", str(case_path), "--samples", str(samples), "--chunk",
            str(chunk), "--seed", "7", "--backend", backend, "--out", str(out), "--json"]


@pytest.mark.slow
@pytest.mark.parametrize("backend", [pytest.param("numpy", marks=pytest.mark.skipif(
    not os.environ.get("QUICKRELEASE_SLOW"), reason="opt-in (QUICKRELEASE_SLOW=1): ~20 s of CPU; a killed numpy uq "
    "run resumed to the same uq.json: tests/cli/test_fault_injection.py::test_killed_uq_resumes_to_the_identical_result, "
    "and 'pass --resume': tests/io/test_runfolder.py")), pytest.param("dask", marks=pytest.mark.skipif(
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


@pytest.mark.slow
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
    from quality import table_faults

    assert table_faults(r.stdout) == []
    assert (tmp_path / "o" / "uq_corner.png").stat().st_size > 20_000
    import hashlib

    prov = json.loads((tmp_path / "o" / "uq.json").read_text(encoding="utf-8"))["provenance"]  # what made it
    assert prov["input"]["sha256"] == hashlib.sha256(Path(case_path).read_bytes()).hexdigest()
    assert prov["input"]["text"] == Path(case_path).read_text(encoding="utf-8")


def _mp_stop_time(a0, aF, F1, F2, k, m2, L1):
    """Eq. 10 by mpmath in the angle itself, E_S implied by the stop at alpha_F (Eq. 8): t = int sqrt(M / (E_S - W_F))
    (M alpha_dot^2 is the kinetic energy, Eq. 5). E_S - W_F(a) = W_F(aF) - W_F(a) is written by sum-to-product,
    2 sin((aF - a) / 2) (2 F1 L1 cos((aF + a) / 2) + 4 F2 L1 sin((aF + a) / 2)), so that it keeps its digits
    next to the stop, where tanh-sinh puts its nodes."""
    import mpmath

    def rest(a):
        m = (aF + a) / 2
        return 2 * mpmath.sin((aF - a) / 2) * (2 * F1 * L1 * mpmath.cos(m) + 4 * F2 * L1 * mpmath.sin(m))

    return mpmath.quad(lambda a: mpmath.sqrt(m2 * L1**2 * (k + mpmath.sin(a) ** 2) / rest(a)), [a0, aF])


@pytest.mark.slow
def test_line_time_partials_against_mpmath():
    """The stop time and its four partials (differentiated under the integral sign, Gauss-Legendre) against an
    independent reference: mpmath's tanh-sinh quadrature of Eq. 10 in alpha, differentiated by central
    differences at 30 digits."""
    import mpmath

    from quickrelease.studies.uq import _line_time_partials

    mpmath.mp.dps = 30
    k, m2, L1 = 2 / 3 * 576.78 / 531.69, 531.69, 2.477
    for a0, aF, F1, F2 in ((0.2, 0.7378, 419.85, 804.57), (0.05, 1.3, 900.0, 30.0), (0.6, 0.65, 0.0, 2000.0)):
        got = _line_time_partials(a0, aF, F1, F2, k, m2, L1)
        x = [mpmath.mpf(v) for v in (a0, aF, F1, F2)]
        t = _mp_stop_time(*x, k, m2, L1)
        assert got["t"] == pytest.approx(float(t), rel=1e-13)
        for i, name in enumerate(("t_alpha0", "t_alpha_final", "t_F1", "t_F2")):
            h = mpmath.mpf("1e-9") * max(abs(x[i]), 1)
            up, dn = list(x), list(x)
            up[i] += h
            dn[i] -= h
            ref = (_mp_stop_time(*up, k, m2, L1) - _mp_stop_time(*dn, k, m2, L1)) / (2 * h)
            assert got[name] == pytest.approx(float(ref), rel=1e-9, abs=1e-15), (a0, name)


@pytest.mark.slow
def test_sensitivities_against_mpmath_identification(case_path):
    """dF1/dx and dF2/dx against an independent chain: (F1, F2) re-identified by mpmath (Eq. 8 for F2 given F1,
    a secant root of the tanh-sinh Eq. 10 for F1) at inputs moved by +-h, central differences (relative step 1e-5: truncation ~1e-10) at 20 digits.
    E_S = P^2 e(alpha0) with e from statics (Eq. 2, tested against Table 3 in test_statics)."""
    import mpmath

    from quickrelease.device.statics import strain_energy_coefficient

    mpmath.mp.dps = 20
    case = load_case(case_path)
    d = case.device
    k = case.mass_factor * d.m1 / d.m2
    ift, fd = sensitivities(case)
    nominal = {"alpha0": case.alpha0, "alpha_final": case.alpha_final, "stop_time": case.stop_time,
               "force": case.push_force}

    def identify(v):
        a0, aF, tF, P = (mpmath.mpf(v[n]) for n in ("alpha0", "alpha_final", "stop_time", "force"))
        # e(alpha0) through floats: a relative step of 1e-5 keeps its rounding (1e-16) below 1e-10 of the slope
        E = P**2 * mpmath.mpf(float(strain_energy_coefficient(float(a0), d)))
        s, c = mpmath.sin(aF) - mpmath.sin(a0), mpmath.cos(a0) - mpmath.cos(aF)

        def f2(F1):
            return (E - 2 * F1 * d.L1 * s) / (4 * d.L1 * c)

        F1 = mpmath.findroot(lambda F1: _mp_stop_time(a0, aF, F1, f2(F1), k, d.m2, d.L1) - tF,
                             (mpmath.mpf(419), mpmath.mpf(420)), solver="secant")
        return F1, f2(F1)

    for name, value in nominal.items():
        h = 1e-5 * abs(value)
        up, dn = dict(nominal), dict(nominal)
        up[name] += h
        dn[name] -= h
        (u1, u2), (d1, d2) = identify(up), identify(dn)
        step = mpmath.mpf(up[name]) - mpmath.mpf(dn[name])
        for f, ref in (("F1", (u1 - d1) / step), ("F2", (u2 - d2) / step)):
            assert ift[f][name] == pytest.approx(float(ref), rel=1e-8), (f, name)
            assert fd[f][name] == pytest.approx(float(ref), rel=1e-5), (f, name)
    # signs: a later stop means more hinge friction (F1 up, F2 down)
    assert ift["F1"]["stop_time"] > 0 > ift["F2"]["stop_time"]
