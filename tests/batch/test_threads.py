"""Threads of the compiled kernels: using_threads, --threads, the same bytes on any count, Dask refuses it."""

import importlib.util
from pathlib import Path

import numba
import numpy as np
import pytest
from conftest import UQ_CASE
from typer.testing import CliRunner

from quickrelease import ParameterError, batch, using_threads
from quickrelease.batch.sampling import random_releases, wide_releases
from quickrelease.cli import app
from quickrelease.io.case import load_case
from quickrelease.studies.distributed import on_one_thread
from quickrelease.studies.planning import release_envelope
from quickrelease.studies.sweep import sweep
from quickrelease.studies.uq import run_uq

EXAMPLES = Path(__file__).parents[2] / "examples"
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
    ["sweep", str(EXAMPLES / "larger_push.toml"), "-g", "alpha0=0.1:0.2:2", "--backend", "dask", "-o", "s.zarr",
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


#: The race probe (run in a subprocess with NUMBA_NUM_THREADS well above the cores): stop times and identifications
#: of a wide sample on one thread, then again on many threads, several times; prints the outputs that differ.
_RACE_PROBE = """
import json, sys
import numba, numpy as np
from quickrelease import batch
from quickrelease.batch.sampling import wide_releases

top = numba.config.NUMBA_NUM_THREADS
assert hasattr(batch, "THREAD_CHUNK")  # the stop-time pool's chunk, read at each call
batch.THREAD_CHUNK = int(sys.argv[2])  # small chunks: many of them, on as many pool threads as numba allows
s = wide_releases(int(sys.argv[1]), seed=21)
cases = [s[k] for k in ("E_S", "alpha0", "F1", "F2", "c", "m1", "m2", "L1")]
numba.set_num_threads(1)
ref = batch.stop_time(*cases)
ok = ref.stopped_by == 0
obs = [s["alpha0"][ok], ref.alpha_final[ok], ref.stop_time[ok], *(s[k][ok] for k in ("E_S", "c", "m1", "m2", "L1"))]

def outputs():
    st, ident = batch.stop_time(*cases), batch.identify(*obs)
    return {**{"stop_" + k: v for k, v in st.to_dict().items()}, **{"id_" + k: v for k, v in ident.to_dict().items()}}

one = outputs()
differ = []
for run, threads in enumerate([top, 3, top, 2, top, top]):
    numba.set_num_threads(threads)
    for key, value in outputs().items():
        if value.tobytes() != one[key].tobytes():
            differ.append(f"{key} on {threads} threads (run {run})")
print(json.dumps({"threads": top, "cases": len(cases[0]), "friction_stops": int(ok.sum()), "differ": differ}))
"""


@pytest.mark.slow
def test_parallel_kernels_free_of_races_on_oversubscribed_threads():
    """Threads sharing scratch memory give wrong bits only when one is preempted mid-case, which a quiet machine with
    as many threads as cores rarely does. Here 16 threads on the machine's cores (the OS preempts them mid-block),
    chunks of 1024 cases in the stop-time pool (dozens of chunks on 16 pool threads), the identification's prange over
    ~200 blocks; six runs on 16, 3 and 2 threads, each compared byte for byte with one thread in the same process.
    Planted races, each caught in 10 runs of this test out of 10 on a 2-core machine: the identification's blocks
    sharing one scratch row, or every fourth block sharing one; the stop-time chunks sharing one N/D buffer, or one
    output buffer for the angle's four numpy steps only (a window of ~50 us a chunk, which the in-process 1-vs-2-thread
    test of test_kernels_wide.py caught 0 times in 5). (``np.empty`` inside the prange body is no race with numba
    0.68: the parfor pass hoists it into the prologue of each thread's share of the loop, not out of the threads.)"""
    import json
    import os
    import subprocess
    import sys

    env = {**os.environ, "NUMBA_NUM_THREADS": "16"}
    run = subprocess.run([sys.executable, "-c", _RACE_PROBE, "60000", "1024"], env=env, capture_output=True,
                         text=True, timeout=600, check=True)
    report = json.loads(run.stdout.strip().splitlines()[-1])
    assert report["threads"] == 16 and report["friction_stops"] > 40_000  # > 160 blocks of the identification
    assert report["differ"] == []
