"""The GPU path (:mod:`quickrelease.batch._gpu`, issue 12 item 4): kernels written once against an array module.

No GPU here: the very same code runs with ``xp = numpy`` and is checked

* against the compiled CPU kernels (:mod:`quickrelease.batch._fast` through :mod:`quickrelease.batch`) to 1e-13 relative:
  stop time, alpha_F, the regime, every field of the release envelope, the identification's F1*, F2* and feasible
  ends, and lambda = F1/F1* to 1e-13 plus its rounding floor ``8 eps t_F / (t_hi - t_lo)`` (an observation whose t_F
  barely changes along the line of Eq. 13 determines lambda no better), on the bench and the wide samples, per tier;
* its tiers against ``_kernels.Releases.build`` (the numpy kernels) and its panel counts against ``_fast._panel_count``;
* on device-array stand-ins that refuse any numpy function but the ufuncs (as CuPy arrays take them), through an
  array module of functions CuPy has: no numpy-only call, and numpy's bits;
* against mpmath (:mod:`quickrelease.device.reference`) on cases of every (regime, tier): 18 stop times and 3
  identifications here, 300 and 60 with QUICKRELEASE_SLOW=1;
* the wiring of ``backend="gpu"`` (batch, uq, sweep) with the array module replaced by numpy.

The same checks on CuPy run where :func:`quickrelease.batch._gpu.gpu_available` (skipped cleanly elsewhere), and the
refusals without CuPy or without a device: one line, exit 2, nothing written.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from quickrelease import QuickReleaseError, batch
from quickrelease.batch import _fast, _gpu
from quickrelease.batch.sampling import random_releases, wide_releases
from quickrelease.cli import app
from quickrelease.device import _kernels
from quickrelease.device.reference import identify_mp, stop_time_mp
from quickrelease.errors import ParameterError

SLOW = bool(os.environ.get("QUICKRELEASE_SLOW"))
KEYS = ("E_S", "alpha0", "F1", "F2", "c", "m1", "m2", "L1")
EPS = np.finfo(float).eps
RTOL = 1e-13
EXAMPLES = Path(__file__).parents[2] / "examples"
runner = CliRunner()
ON_GPU = _gpu.gpu_available()


def _cases(sample: str, n: int) -> dict[str, np.ndarray]:
    cases = (random_releases if sample == "bench" else wide_releases)(n, seed=7)
    cases["k"] = cases["c"] * cases["m1"] / cases["m2"]
    return cases


@pytest.fixture(scope="module", params=["bench", "wide"])
def sample(request):
    """A sample, its compiled CPU answers and the (regime, tier) of each case (numpy kernels)."""
    cases = _cases(request.param, 20_000)
    cases["cpu"] = batch.stop_time(*(cases[key] for key in KEYS))
    rel = _kernels.Releases.build(*(cases[key] for key in ("E_S", "alpha0", "F1", "F2", "k", "m2", "L1")))
    cases["tier"], cases["regime"] = rel.tier, rel.regime
    cases["name"] = request.param
    return cases


def _args(cases, xp=np):
    return [xp.asarray(cases[key]) for key in ("E_S", "alpha0", "F1", "F2", "k", "m2", "L1")]


def _conditioning(cases, ulps: float = 4.0) -> np.ndarray:
    """The most relative change of t_F (compiled CPU kernels) when E_S, alpha0, F1, F2 or c moves by ``ulps`` ulps.

    A GPU's sine and cosine are within 2 ulps, not correctly rounded: a case whose t_F is ill-conditioned in its
    inputs (the graded tier of a limit stop, where the margin to pi/2 is small: one ulp of alpha0 moves t_F by up
    to 1e-9 relative in the wide sample) may differ from the CPU by that much on any backend. Measured on an H200
    (2026-11-26): 228 of 20 000 wide cases beyond 1e-13, the largest 1.7e-9, each within 0.33 of this bound, and
    within a few times of the CPU's own error against mpmath there."""
    if "conditioning" not in cases:
        cpu = cases["cpu"].stop_time
        sens = np.zeros_like(cpu)
        for key in ("E_S", "alpha0", "F1", "F2", "c"):
            for sign in (1.0, -1.0):
                moved = dict(cases, **{key: cases[key] * (1.0 + sign * ulps * EPS)})
                other = batch.stop_time(*(moved[name] for name in KEYS)).stop_time
                with np.errstate(invalid="ignore"):
                    sens = np.fmax(sens, np.abs(other / cpu - 1.0))
        cases["conditioning"] = sens
    return cases["conditioning"]


def _check_stop(cases, t, aF, code, borderline=0):
    """As the compiled kernels, to RTOL per (regime, tier). ``borderline``: how many cases may be classified or
    tiered otherwise and then differ by up to 2e-12 (a GPU's sine, 2 ulps, moves a margin or a tier criterion
    within rounding of its threshold; the numpy path computes what the compiled setup does: none)."""
    cpu = cases["cpu"]
    same = code == cpu.stopped_by
    assert np.sum(~same) <= borderline
    assert np.array_equal(np.isinf(t[same]), np.isinf(cpu.stop_time[same]))
    assert np.sum(np.abs(aF[same] / cpu.alpha_final[same] - 1.0) > RTOL) <= borderline
    finite = np.isfinite(cpu.stop_time) & same
    err = np.abs(t[finite] / cpu.stop_time[finite] - 1.0)
    if borderline:  # on a GPU: within RTOL plus what 4 ulps of the inputs move t_F by (the compiled kernels say)
        assert np.all(err <= RTOL + _conditioning(cases)[finite]), np.max(err / (RTOL + _conditioning(cases)[finite]))
    else:
        assert np.sum(err > RTOL) <= borderline and np.all(err <= 2e-12)
    for regime in (0, 1):
        for tier in (0, 1, 2):
            cls = ((cases["regime"] == regime) & (cases["tier"] == tier))[finite]
            if cls.any() and not borderline:
                assert np.max(err[cls]) <= RTOL, (regime, tier, np.max(err[cls]))
    return err


def test_stop_time_as_the_compiled_kernels_per_tier(sample):
    t, aF, code = _gpu.stop_arrays(np, *_args(sample), chunk=4096)  # several chunks
    _check_stop(sample, t, aF, code)
    if sample["name"] == "wide":  # the wide sample hits every class
        for regime in (0, 1):
            for tier in (0, 1, 2):
                assert ((sample["regime"] == regime) & (sample["tier"] == tier)).sum() >= 20, (regime, tier)


def test_tiers_and_panel_counts_as_the_cpu_kernels(sample):
    """The xp path's tier of each case is that of the numpy kernels (the one criterion, ``_kernels.tier_of``, but
    the compiled kernels' setup: the chord from (N, D), no sine), but for cases within rounding of a threshold;
    its graded panel counts those of ``_fast._panel_count``."""
    c = _gpu._setup(np, *_args(sample))
    live = sample["regime"] != 2
    assert np.array_equal(c["regime"], sample["regime"])
    assert np.sum(c["tier"][live] != sample["tier"][live]) <= 2
    distances = np.concatenate([[0.0, -1.0, np.nan, np.inf, 1e-300, 0.5, 1.0, 4.0], 10.0 ** np.linspace(-14, 0.5, 400),
                                0.5 * _kernels.GRADING ** np.arange(18)])
    got = _gpu.panel_counts(np, distances)
    want = [_fast._panel_count(d, _kernels.GRADING, _fast.GRADED_REACH, _kernels.N_PANELS) for d in distances]
    assert np.array_equal(got, want)


def test_graded_tier_with_only_the_panels_it_needs(sample):
    """Fewer panels than the full graded rule, the same answer (within 1e-14 of ``_kernels.graded_unit``)."""
    graded = (sample["tier"] == 2) & (sample["regime"] != 2)
    if graded.sum() < 50:
        pytest.skip("few graded cases in the bench sample")
    sub = {key: sample[key][graded] for key in ("E_S", "alpha0", "F1", "F2", "k", "m2", "L1")}
    c = _gpu._setup(np, *_args(sub))
    jl = _gpu.panel_counts(np, np.sqrt(np.maximum(c["ratio"], 0.0)))
    jr = _gpu.panel_counts(np, 0.5 * np.sqrt(c["msq"]))
    assert np.mean(jl + jr) < 2 * _kernels.N_PANELS - 4  # most cases need far fewer than all 34 panels
    t = _gpu.stop_arrays(np, *_args(sub))[0]
    rel = _kernels.Releases.build(*(sub[key] for key in ("E_S", "alpha0", "F1", "F2", "k", "m2", "L1")))
    x, wt = _kernels.graded_unit()
    full = rel.integrand(np.broadcast_to(x, (t.size, x.size))) @ wt
    assert np.max(np.abs(t / full - 1.0)) < 1e-14


def _observations(cases, n=None):
    cpu = cases["cpu"]
    ok = np.nonzero(cpu.stopped_by == 0)[0][:n]
    return ok, [cases["alpha0"][ok], cpu.alpha_final[ok], cpu.stop_time[ok], cases["E_S"][ok]]


def _check_identify(got, ref, t_F, tier, borderline=0):
    """As the compiled kernel: F1*, F2* and the ends to RTOL, lambda to RTOL plus its rounding floor, per tier;
    ``borderline`` cases may differ (see :func:`_check_stop`: a status or a tier decided within rounding)."""
    same = got["status"] == ref.status
    assert np.sum(~same) <= borderline
    for name in ("F1_max", "F2_max", "stop_time_min", "stop_time_max"):
        err = np.abs(got[name] / getattr(ref, name) - 1.0)
        assert np.sum(err > RTOL) <= borderline and np.all(err <= 2e-12), name
    ok = (ref.status == 0) & same
    floor = 8.0 * EPS * t_F / (ref.stop_time_max - ref.stop_time_min)  # lambda's rounding floor
    dlam = np.abs(got["lam"] * got["F1_max"] - ref.F1) / ref.F1_max
    for tr in (0, 1, 2):
        cls = ok & (tier == tr)
        assert np.sum(dlam[cls] > RTOL + floor[cls]) <= borderline, (tr, np.max(dlam[cls] / (RTOL + floor[cls])))
    assert np.sum(np.abs(got["iterations"].astype(int) - ref.iterations) > 1) <= borderline


def test_identification_as_the_compiled_kernel_per_tier(sample):
    ok, obs = _observations(sample)
    k, m2, L1 = sample["k"][ok], sample["m2"][ok], sample["L1"][ok]
    i = np.arange(ok.size)
    t_F = obs[2] * np.where(i % 3 == 0, 1.0, 1.0 + 1e-6 * (i % 7 - 3)) * np.where(i % 11 == 5, 3.0, 1.0) \
        * np.where(i % 13 == 5, 0.3, 1.0)
    obs[2] = t_F  # observations off the model: some infeasible (statuses 1 and 2), the rest at other lambdas
    ref = batch.identify(*obs, sample["c"][ok], sample["m1"][ok], m2, L1)
    assert {1, 2} <= set(np.unique(ref.status)) and np.mean(ref.status == 0) > 0.5
    got = _gpu.identify_arrays(np, *obs, k, m2, L1, chunk=4096)
    tier = _kernels.tier_of(np.cos(obs[1]) / np.cos(0.5 * (obs[1] + obs[0])),
                            (k + np.sin(obs[0]) ** 2) / (obs[1] - obs[0]) ** 2)
    _check_identify(got, ref, t_F, tier)


def test_release_envelope_as_the_compiled_kernels(sample):
    sub = {key: sample[key][:3000] for key in KEYS + ("k",)}
    cpu = batch.release(*(sub[key] for key in KEYS))
    got = _gpu.release_arrays(np, *_args(sub), chunk=1024)
    assert np.array_equal(got["stopped_by"], cpu.stopped_by)
    for name in ("stop_time", "alpha_final", "u_final", "v_final", "alpha_dot0", "peak_u_dot", "peak_v_dot",
                 "peak_u_ddot", "peak_v_ddot"):
        ref = getattr(cpu, name)
        fin = np.isfinite(ref)
        assert np.max(np.abs(got[name][fin] / ref[fin] - 1.0)) <= RTOL, name


# -- only what numpy and CuPy share ----------------------------------------------------------------------------------

class _DeviceArray(np.ndarray):
    """Stands for a CuPy array: numpy ufuncs work on it (CuPy's ``__array_ufunc__``), any other numpy function called
    on it (np.where, np.clip, np.argmax, ...: numpy-only code) raises."""

    def __array_function__(self, func, types, args, kwargs):
        raise TypeError(f"numpy.{func.__name__} called on a device array: use the array module")


def _plain(v):
    return v.view(np.ndarray) if isinstance(v, np.ndarray) else v


def _strict_module():
    """An array module with only functions CuPy has too (each takes and returns device arrays)."""
    import types

    mod = types.SimpleNamespace(inf=np.inf, nan=np.nan, int8=np.int8, int16=np.int16, int64=np.int64,
                                float64=np.float64)
    for name in ("sin", "cos", "sqrt", "hypot", "arctan2", "log", "ceil", "minimum", "maximum", "abs", "isnan",
                 "isfinite"):
        setattr(mod, name, getattr(np, name))  # ufuncs: CuPy has each
    for name in ("where", "asarray", "empty", "zeros", "ones", "full", "arange", "nonzero", "argmax", "unique",
                 "concatenate", "any", "max"):
        setattr(mod, name, _on_device(getattr(np, name)))
    return mod


def _to_device(v):
    return v.view(_DeviceArray) if isinstance(v, np.ndarray) else v


def _on_device(func):
    """``func`` of numpy on the plain arrays behind device arrays, its arrays returned as device arrays."""
    def call(*args, **kwargs):
        args = [[_plain(v) for v in a] if isinstance(a, list) else _plain(a) for a in args]
        out = func(*args, **{k: _plain(v) for k, v in kwargs.items()})
        return tuple(_to_device(v) for v in out) if isinstance(out, tuple) else _to_device(out)
    return call


def test_the_kernels_use_only_what_numpy_and_cupy_share():
    """Run on device stand-ins, the kernels call no numpy-only function (and give numpy's bits); the functions of
    dynamics and _kernels they call are arithmetic and numpy ufuncs only."""
    import inspect
    import re

    from quickrelease.device import dynamics

    for fn in (dynamics.amplitude_terms, dynamics.limit_margin_terms, dynamics._limit_dissipation, dynamics.one_minus_sin_terms,
               dynamics.creeps_terms, dynamics.limit_sweep, dynamics._stop_terms, dynamics.sweep_sides,
               _kernels.feasible_slack):
        for name in re.findall(r"\bnp\.(\w+)", inspect.getsource(fn).split('"""')[-1]):
            assert isinstance(getattr(np, name), np.ufunc), (fn.__name__, name)
    cases = _cases("wide", 3000)
    xp = _strict_module()
    dev = [xp.asarray(v) for v in _args(cases)]
    with pytest.raises(TypeError, match="numpy.where called on a device array"):
        np.where(dev[0] > 0, dev[0], 0.0)
    got = _gpu.stop_arrays(xp, *dev, chunk=1000)
    want = _gpu.stop_arrays(np, *_args(cases), chunk=1000)
    assert all(type(g) is _DeviceArray and np.array_equal(_plain(g), w) for g, w in zip(got, want, strict=True))
    env = _gpu.release_arrays(xp, *dev, chunk=1000)
    assert all(np.array_equal(_plain(v), w, equal_nan=True)
               for v, w in zip(env.values(), _gpu.release_arrays(np, *_args(cases), chunk=1000).values(), strict=True))
    fr = want[2] == 0
    obs = [cases["alpha0"][fr], want[1][fr], want[0][fr], cases["E_S"][fr], cases["k"][fr], cases["m2"][fr],
           cases["L1"][fr]]
    got = _gpu.identify_arrays(xp, *(xp.asarray(v) for v in obs), chunk=1000)
    want = _gpu.identify_arrays(np, *obs, chunk=1000)
    assert all(np.array_equal(_plain(got[k]), want[k], equal_nan=True) for k in want)


# -- against mpmath ------------------------------------------------------------------------------------------------

def _picks(cases, per_class):
    out = []
    for regime in (0, 1):
        for tier in (0, 1, 2):
            out.append(np.nonzero((cases["regime"] == regime) & (cases["tier"] == tier))[0][:per_class])
    return np.concatenate(out)


@pytest.fixture(scope="module")
def wide():
    cases = _cases("wide", 20_000)
    rel = _kernels.Releases.build(*(cases[key] for key in ("E_S", "alpha0", "F1", "F2", "k", "m2", "L1")))
    cases["tier"], cases["regime"] = rel.tier, rel.regime
    return cases


@pytest.mark.slow
def test_stop_time_against_mpmath_every_tier(wide):
    pick = _picks(wide, 50 if SLOW else 3)
    sub = {key: v[pick] for key, v in wide.items()}
    t, aF, _ = _gpu.stop_arrays(np, *_args(sub))
    for i in range(pick.size):
        args = [sub[key][i] for key in ("E_S", "alpha0", "F1", "F2", "k", "m2", "L1")]
        ref, ref_aF = stop_time_mp(*args)
        err = abs(t[i] / ref - 1.0)
        if err > 1e-12:  # where one ulp of E_S moves t_F by more (the margin to pi/2 ill-conditioned)
            sens = abs(stop_time_mp(np.nextafter(args[0], np.inf), *args[1:])[0] / ref - 1.0)
            assert err <= 4.0 * sens, (i, err, sens, sub["tier"][i], sub["regime"][i])
        assert abs(aF[i] - ref_aF) <= 4.0 * EPS * ref_aF + 1e-13 * (ref_aF - args[1]), i


@pytest.mark.slow
def test_identification_against_mpmath(wide):
    cpu = batch.stop_time(*(wide[key] for key in KEYS))
    friction = np.nonzero(cpu.stopped_by == 0)[0]
    rel_tier = wide["tier"][friction]
    pick = np.concatenate([friction[rel_tier == tr][:(20 if SLOW else 1)] for tr in (0, 1, 2)])
    a0, aF, tF, E = wide["alpha0"][pick], cpu.alpha_final[pick], cpu.stop_time[pick], wide["E_S"][pick]
    k, m2, L1 = wide["k"][pick], wide["m2"][pick], wide["L1"][pick]
    got = _gpu.identify_arrays(np, a0, aF, tF, E, k, m2, L1)
    assert np.all(got["status"] == 0)
    spread = tF / (got["stop_time_max"] - got["stop_time_min"])
    # an observation within FEASIBLE_RTOL of an end of the feasible interval is that end (F1 = 0 or F2 = 0), as on
    # the CPU: lambda may then be off by that much over the slope of t(lambda)
    at_end = (got["lam"] == 0.0) | (got["lam"] == 1.0)
    tol = 1e-12 + (64.0 * EPS + np.where(at_end, 2.0 * _kernels.FEASIBLE_RTOL, 0.0)) * spread
    for i in range(pick.size):
        F1 = got["lam"][i] * got["F1_max"][i]
        F1_mp, F2_mp = identify_mp(a0[i], aF[i], tF[i], E[i], k[i], m2[i], L1[i], start=F1 if F1 > 0 else None)
        assert abs(F1 - F1_mp) <= tol[i] * got["F1_max"][i], i
        assert abs((1.0 - got["lam"][i]) * got["F2_max"][i] - F2_mp) <= tol[i] * got["F2_max"][i], i


# -- on CuPy, where there is a GPU ---------------------------------------------------------------------------------

@pytest.mark.skipif(not ON_GPU, reason="no CUDA GPU with CuPy here")
def test_on_the_gpu_as_the_compiled_kernels(sample):
    import cupy

    t, aF, code = (_gpu.to_host(v) for v in _gpu.stop_arrays(cupy, *_args(sample, cupy)))
    _check_stop(sample, t, aF, code, borderline=sample["E_S"].size // 5000)
    ok, obs = _observations(sample)
    k, m2, L1 = sample["k"][ok], sample["m2"][ok], sample["L1"][ok]
    ref = batch.identify(*obs, sample["c"][ok], sample["m1"][ok], m2, L1)
    got = {key: _gpu.to_host(v) for key, v in _gpu.identify_arrays(cupy, *(cupy.asarray(v) for v in (*obs, k, m2, L1))
                                                                    ).items()}
    tier = _kernels.tier_of(np.cos(obs[1]) / np.cos(0.5 * (obs[1] + obs[0])),
                            (k + np.sin(obs[0]) ** 2) / (obs[1] - obs[0]) ** 2)
    _check_identify(got, ref, obs[2], tier, borderline=obs[0].size // 5000)
    got = batch.release(*(sample[key][:3000] for key in KEYS), backend="gpu")
    cpu = batch.release(*(sample[key][:3000] for key in KEYS))
    for name in ("stop_time", "alpha_final", "u_final", "v_final", "alpha_dot0", "peak_u_dot", "peak_v_dot",
                 "peak_u_ddot", "peak_v_ddot"):
        ref = getattr(cpu, name)
        fin = np.isfinite(ref) & (got.stopped_by == cpu.stopped_by)
        err = np.abs(getattr(got, name)[fin] / ref[fin] - 1.0)
        if name == "stop_time":
            assert np.all(err <= RTOL + _conditioning(sample)[:3000][fin]), name
        else:
            assert np.sum(err > RTOL) <= 1, name


# -- the backend's wiring, with numpy standing in for CuPy -----------------------------------------------------------

@pytest.fixture
def numpy_gpu(monkeypatch):
    """``backend="gpu"`` run by the xp kernels on numpy (the device check passed, the array module numpy)."""
    import quickrelease.studies.distributed as distributed

    monkeypatch.setattr(_gpu, "array_module", lambda: np)
    monkeypatch.setattr(_gpu, "require_gpu", lambda: None)
    real = distributed._installed
    monkeypatch.setattr(distributed, "_installed", lambda name: name == "cupy" or real(name))


def test_batch_backend_gpu_wiring(numpy_gpu):
    cases = wide_releases(2000, seed=3)
    cases["E_S"][:3] = [np.inf, -1.0, np.nan]  # screened: NaN, status 1
    args = [cases[key].reshape(40, 50) for key in KEYS]  # broadcast shapes kept
    for fn in (batch.stop_time, batch.release):
        cpu, gpu = fn(*args), fn(*args, backend="gpu")
        for name, v in cpu.to_dict().items():
            w = getattr(gpu, name)
            assert w.shape == v.shape and np.array_equal(np.isnan(w), np.isnan(v)), name
            fin = np.isfinite(v) & (v != 0)
            assert np.max(np.abs(w[fin] / v[fin] - 1.0)) <= RTOL, name
    st = batch.stop_time(*args)
    obs = (args[1], st.alpha_final * np.where(np.arange(50) == 7, 0.0, 1.0), st.stop_time, args[0])  # some invalid
    cpu, gpu = batch.identify(*obs, *args[4:]), batch.identify(*obs, *args[4:], backend="gpu")
    assert np.array_equal(cpu.status, gpu.status) and {3, 5} <= set(np.unique(cpu.status))
    ok = cpu.status == 0
    assert np.all(np.abs(gpu.F1[ok] - cpu.F1[ok]) <= (RTOL + 8 * EPS * obs[2][ok] / (
        cpu.stop_time_max[ok] - cpu.stop_time_min[ok])) * cpu.F1_max[ok])


def test_sweep_and_uq_backend_gpu_wiring(numpy_gpu, tmp_path):
    from quickrelease.io.case import load_case
    from quickrelease.studies.sweep import sweep
    from quickrelease.studies.uq import run_uq

    case = load_case(EXAMPLES / "larger_push.toml")
    grids = {"alpha0": np.linspace(0.1, 0.5, 4), "F1": np.linspace(100.0, 4000.0, 5)}
    a, b = sweep(case, grids), sweep(case, grids, backend="gpu")
    for name in ("stop_time", "u_final", "peak_u_ddot"):
        assert np.max(np.abs(b[name].values / a[name].values - 1.0)) <= RTOL, name
    with pytest.raises(ParameterError, match="threads"):
        sweep(case, grids, backend="gpu", threads=1)
    case = load_case(EXAMPLES / "uq_paper.toml")
    a, b = run_uq(case, 3000, chunk=1000, figures=False), run_uq(case, 3000, chunk=1000, backend="gpu", figures=False)
    assert a.status_counts == b.status_counts
    for name in ("F1", "F2"):
        assert abs(b.mean[name] / a.mean[name] - 1.0) < 1e-12
        for key, v in a.percentiles[name].items():  # (a sample may cross a bin edge by an ulp: one bin at most)
            assert abs(b.percentiles[name][key] - v) <= a.resolution[name], (name, key)
    r = runner.invoke(app, ["uq", str(EXAMPLES / "uq_paper.toml"), "--samples", "3000", "--chunk", "1000", "--backend",
                            "gpu", "--json"])
    assert r.exit_code == 0, r.output
    cli = json.loads(r.stdout)["percentiles_N"]["F1"]
    assert all(abs(cli[key] - v) <= a.resolution["F1"] for key, v in a.percentiles["F1"].items())


# -- refusals ------------------------------------------------------------------------------------------------------

def _one_line_exit_2(r, *words):
    assert r.exit_code == 2, r.output
    assert "Traceback" not in r.output and r.stderr.count("\n") == 1, r.output
    for word in words:
        assert word in r.stderr, (word, r.stderr)


def _commands(tmp_path):
    return {"uq": ["uq", str(EXAMPLES / "uq_paper.toml"), "--out", str(tmp_path / "o")],
            "sweep": ["sweep", str(EXAMPLES / "larger_push.toml"), "--grid", "alpha0=0.1:0.5:3", "--out",
                      str(tmp_path / "s.nc")]}


@pytest.mark.parametrize("command", ["uq", "sweep"])
def test_backend_gpu_without_cupy(monkeypatch, tmp_path, command):
    monkeypatch.setitem(sys.modules, "cupy", None)  # as Python sees a missing package
    r = runner.invoke(app, [*_commands(tmp_path)[command], "--backend", "gpu"])
    _one_line_exit_2(r, "the gpu backend needs cupy", "pip install 'quickrelease[gpu]'")
    assert list(tmp_path.iterdir()) == []  # nothing written, no output folder half made


@pytest.mark.parametrize("command", ["uq", "sweep"])
def test_backend_gpu_without_a_device(monkeypatch, tmp_path, command):
    import quickrelease.studies.distributed as distributed

    real = distributed._installed
    monkeypatch.setattr(distributed, "_installed", lambda name: name == "cupy" or real(name))
    monkeypatch.setattr(_gpu, "_cupy_installed", lambda: True)
    monkeypatch.setattr(_gpu, "gpu_available", lambda: False)
    r = runner.invoke(app, [*_commands(tmp_path)[command], "--backend", "gpu"])
    _one_line_exit_2(r, "the gpu backend needs a CUDA device")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command", ["uq", "sweep"])
def test_threads_refused_with_the_gpu_backend(tmp_path, command):
    r = runner.invoke(app, [*_commands(tmp_path)[command], "--backend", "gpu", "--threads", "1"])
    _one_line_exit_2(r, "--threads", "gpu backend")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(ON_GPU, reason="a GPU is here")
def test_api_refuses_without_a_gpu(monkeypatch, tmp_path):
    from quickrelease.io.case import load_case
    from quickrelease.studies.uq import run_uq

    monkeypatch.setitem(sys.modules, "cupy", None)
    for fn, args in ((batch.stop_time, (1e3, 0.5, 100.0, 100.0)), (batch.release, (1e3, 0.5, 100.0, 100.0)),
                     (batch.identify, (0.5, 0.6, 0.5, 1e3))):
        with pytest.raises(QuickReleaseError, match=r"needs cupy .*quickrelease\[gpu\]"):
            fn(*args, backend="gpu")
    with pytest.raises(QuickReleaseError, match=r"quickrelease\[gpu\]"):
        run_uq(load_case(EXAMPLES / "uq_paper.toml"), 100, backend="gpu", out=tmp_path / "o")
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ParameterError, match="backend = cuda"):
        batch.stop_time(1e3, 0.5, 100.0, 100.0, backend="cuda")
    assert not _gpu.gpu_available()


# -- quickrelease bench's GPU section --------------------------------------------------------------------------------

def test_bench_gpu_section(numpy_gpu, monkeypatch):
    """Without a GPU: None and one line saying so; with one (numpy standing in): throughput and agreement."""
    from quickrelease.studies import bench

    sizes = bench.Sizes(cases=300, stop_time=1, identify=1, repeat=1)
    log: list[str] = []
    monkeypatch.setattr(_gpu, "gpu_available", lambda: False)
    assert bench._gpu_section(sizes, 0, log.append) is None and "no GPU found" in log[0]
    monkeypatch.setattr(_gpu, "gpu_available", lambda: True)
    monkeypatch.setattr(_gpu, "device_name", lambda: ("numpy stand-in", "0"))
    out = bench._gpu_section(sizes, 0, log.append)
    json.dumps(out, allow_nan=False)
    assert out["device"] == "numpy stand-in"
    for sample in ("bench", "wide"):
        g = out[sample]
        assert g["cases"] == bench.GPU_SCALE * 300 and g["stop_time_cases_per_s"] > 0
        assert g["stop_time_max_rel_diff"] <= RTOL and g["alpha_final_max_rel_diff"] <= RTOL
        assert g["identify_ends_max_rel_diff"] <= RTOL and g["identify_F1_max_diff_over_tolerance"] <= 1.0
        assert g["stopped_by_identical"] and g["identify_status_identical"]


def test_device_chunk_from_the_free_memory():
    """A quarter of the free device memory at BYTES_PER_CASE a case, as a power of two in [CHUNK, MAX_CHUNK]."""
    from types import SimpleNamespace

    def fake(free):
        return SimpleNamespace(cuda=SimpleNamespace(runtime=SimpleNamespace(memGetInfo=lambda: (free, 2 * free))))

    assert _gpu.device_chunk(np) == _gpu.CHUNK
    assert _gpu.device_chunk(fake(140 * 2**30)) == 1 << 22  # an H200: capped
    assert _gpu.device_chunk(fake(16 * 2**30)) == 1 << 21  # 2^21 cases x 2 kB = 4 GiB, a quarter of 16 GiB
    assert _gpu.device_chunk(fake(16 * 2**30 - 1)) == 1 << 20
    assert _gpu.device_chunk(fake(2**30)) == _gpu.CHUNK  # never below CHUNK
