"""Threads of the compiled kernels: using_threads, --threads, the same bytes on any count, Dask refuses it."""

import importlib.util
from pathlib import Path

import numba
import numpy as np
import pytest
from conftest import UQ_CASE
from typer.testing import CliRunner

from quickrelease import ParameterError, batch, using_threads
from quickrelease.case import load_case
from quickrelease.cli import app
from quickrelease.distributed import on_one_thread
from quickrelease.planning import release_envelope
from quickrelease.sampling import random_releases, wide_releases
from quickrelease.sweep import sweep
from quickrelease.uq import run_uq

EXAMPLES = Path(__file__).parent.parent / "examples"
TOP = numba.config.NUMBA_NUM_THREADS
two_threads = pytest.mark.skipif(TOP < 2, reason="numba may use one thread only here (NUMBA_NUM_THREADS)")
runner = CliRunner()


@pytest.fixture()
def uq_case(tmp_path):
    path = tmp_path / "uq.toml"
    path.write_text(UQ_CASE)
    return load_case(path)


@pytest.mark.parametrize("bad", [0, -1, TOP + 1, 1.5, True, "2"])
def test_bad_thread_counts_name_the_parameter_and_range(bad):
    before = numba.get_num_threads()
    with pytest.raises(ParameterError, match=rf"threads = {bad} is outside integers in \[1, {TOP}\]"):
        with using_threads(bad):
            pass
    assert numba.get_num_threads() == before


def test_count_is_set_inside_and_restored_after_even_on_error():
    before = numba.get_num_threads()
    with using_threads(1) as n:
        assert n == 1 and numba.get_num_threads() == 1
        with using_threads(TOP) as inner:  # nested: the inner count, then the outer one again
            assert inner == TOP and numba.get_num_threads() == TOP
        assert numba.get_num_threads() == 1
    assert numba.get_num_threads() == before
    with pytest.raises(RuntimeError), using_threads(1):
        raise RuntimeError("inside")
    assert numba.get_num_threads() == before
    with using_threads(None) as n:  # None: numba's current count, untouched
        assert n == before == numba.get_num_threads()


def _same_bytes(a, b):
    assert a.keys() == b.keys()
    for k in a:
        assert np.asarray(a[k]).tobytes() == np.asarray(b[k]).tobytes(), k


@two_threads
@pytest.mark.parametrize("sample", [random_releases, wide_releases])
def test_batch_kernels_give_the_same_bytes_on_one_and_two_threads(sample):
    # more cases than a chunk, so that a parallel kernel splits the work; the wide sample takes every tier
    cases = sample(3 * batch.CHUNK + 17, seed=5)
    out = {}
    for n in (1, 2):
        with using_threads(n):
            st = batch.stop_time(**cases)
            fr = st.stopped_by == 0
            ident = batch.identify(cases["alpha0"][fr], st.alpha_final[fr], st.stop_time[fr], cases["E_S"][fr],
                                   cases["c"][fr], cases["m1"][fr], cases["m2"][fr], cases["L1"][fr])
            rel = batch.release(**{k: v[:2000] for k, v in cases.items()})
        out[n] = {**{f"st_{k}": v for k, v in st.to_dict().items()},
                  **{f"id_{k}": v for k, v in ident.to_dict().items()},
                  **{f"rel_{k}": v for k, v in rel.to_dict().items()}}
    assert np.isfinite(out[1]["id_F1"][out[1]["id_status"] == 0]).all()
    _same_bytes(out[1], out[2])


@two_threads
def test_uq_sweep_and_envelope_give_the_same_bytes_on_one_and_two_threads(uq_case):
    a = run_uq(uq_case, 30_000, seed=4, chunk=10_000, threads=1)
    b = run_uq(uq_case, 30_000, seed=4, chunk=10_000, threads=2)
    assert a.summary() == b.summary()
    plan = load_case(EXAMPLES / "plan.toml")
    ea, eb = release_envelope(plan, samples=5000, threads=1), release_envelope(plan, samples=5000, threads=2)
    _same_bytes(ea.values, eb.values)
    case = load_case(EXAMPLES / "larger_push.toml")
    grids = {"force": np.linspace(500e3, 3000e3, 40), "alpha0": np.linspace(0.05, 1.3, 60)}
    sa, sb = sweep(case, grids, threads=1), sweep(case, grids, threads=2)
    _same_bytes({k: sa[k].values for k in sa.data_vars}, {k: sb[k].values for k in sb.data_vars})


_HAS_DASK = all(importlib.util.find_spec(m) is not None for m in ("dask", "distributed", "zarr"))


def test_api_validates_threads_before_any_work(uq_case, tmp_path):
    with pytest.raises(ParameterError, match=r"threads = 0 is outside integers in \[1,"):
        run_uq(uq_case, 100, threads=0, out=tmp_path / "run")
    assert [p.name for p in tmp_path.iterdir()] == ["uq.toml"]  # nothing written
    if _HAS_DASK:  # without the [dask] extra the missing packages are reported first (one line too)
        with pytest.raises(ParameterError, match="threads = 2 is outside the numpy backend"):
            run_uq(uq_case, 100, threads=2, backend="dask")
        case = load_case(EXAMPLES / "larger_push.toml")
        with pytest.raises(ParameterError, match="threads = 1 is outside the numpy backend"):
            sweep(case, {"alpha0": np.array([0.2])}, backend="dask", out=tmp_path / "s.zarr", threads=1)
    with pytest.raises(ParameterError, match=r"threads = 0 is outside integers"):
        release_envelope(load_case(EXAMPLES / "plan.toml"), samples=10, threads=0)


def test_a_dask_task_runs_on_one_thread():
    before = numba.get_num_threads()
    assert on_one_thread(numba.get_num_threads) == 1
    assert numba.get_num_threads() == before


@pytest.mark.parametrize("args", [
    ["uq", str(EXAMPLES / "uq_paper.toml"), "--backend", "dask", "--threads", "2", "-n", "10"],
    ["uq", str(EXAMPLES / "uq_paper.toml"), "--threads", "0", "-n", "10"],
    ["sweep", str(EXAMPLES / "larger_push.toml"), "-g", "alpha0=0.1:0.2:2", "--backend", "dask", "-f", "s.zarr",
     "--threads", "1"],
    ["plan", str(EXAMPLES / "plan.toml"), "--threads", str(TOP + 1)],
])
def test_cli_refuses_bad_threads_in_one_line(args, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = runner.invoke(app, args)
    assert r.exit_code == 2, r.output
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: --threads = "), r.stderr
    assert not any(tmp_path.iterdir())  # nothing written


def test_cli_threads_runs(tmp_path):
    r = runner.invoke(app, ["uq", str(EXAMPLES / "uq_paper.toml"), "-n", "2000", "--threads", "1", "--json"])
    assert r.exit_code == 0, r.output
    r2 = runner.invoke(app, ["uq", str(EXAMPLES / "uq_paper.toml"), "-n", "2000", "--json"])
    assert r2.stdout == r.stdout


def test_the_kernels_run_on_the_threads_asked_for(uq_case, monkeypatch):
    """Wiring: inside uq, sweep and the release envelope the batch kernels see the count given by threads=."""
    seen = []

    def spy(kernel):
        def wrapped(*args, **kwargs):
            seen.append(numba.get_num_threads())
            return kernel(*args, **kwargs)
        return wrapped

    monkeypatch.setattr(batch, "release", spy(batch.release))
    monkeypatch.setattr(batch, "identify", spy(batch.identify))
    run_uq(uq_case, 1000, threads=1)
    sweep(load_case(EXAMPLES / "larger_push.toml"), {"alpha0": np.array([0.2, 0.3])}, threads=1)
    release_envelope(load_case(EXAMPLES / "plan.toml"), samples=10, threads=1)
    assert len(seen) >= 3 and set(seen) == {1}
    seen.clear()
    run_uq(uq_case, 1000)  # default: numba's count (all cores unless changed)
    assert set(seen) == {numba.get_num_threads()} == {TOP}
