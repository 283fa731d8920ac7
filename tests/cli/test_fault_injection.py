"""Fault injection (issue 9, "What it must show"): SIGKILL ``run``, ``sweep`` (numpy to NetCDF and Zarr, Dask
to Zarr) and ``uq`` at seeded random points; what is left must be nothing, the previous complete result, or
an unfinished run beside ``--out`` that ``--resume`` completes to the bit-identical result, and that refuses
a resume with a changed input. The kill points are drawn from a seeded generator; whatever state a kill
leaves, the checks below must hold (no assertion depends on timing)."""

import importlib.util
import json
import os
import random
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import UQ_CASE

from quickrelease.io.case import load_case
from quickrelease.studies.sweep import sweep
from quickrelease.studies.uq import run_uq
from quickrelease.workflow import run_case, write_results

EXAMPLES = Path(__file__).parents[2] / "examples"
HAS_DASK = importlib.util.find_spec("dask") is not None and importlib.util.find_spec("distributed") is not None \
    and importlib.util.find_spec("zarr") is not None
HAS_ZARR = importlib.util.find_spec("zarr") is not None
RNG = random.Random(20261123)


def _cmd(*args):
    return [sys.executable, "-m", "quickrelease.cli", *[str(a) for a in args]]


def _kill(cmd, delay, ready=None, limit=120.0):
    """Start ``cmd``; once ``ready()`` holds (or at once), wait ``delay`` s and SIGKILL its process group
    (Dask workers included). Returns the exit code: 0 when it finished before the kill, negative if killed."""
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True)
    deadline = time.monotonic() + limit
    while ready is not None and proc.poll() is None and not ready() and time.monotonic() < deadline:
        time.sleep(0.02)
    try:
        proc.wait(timeout=delay)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    else:
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # leftover workers of a finished run
        except ProcessLookupError:
            pass
    err = proc.stderr.read().decode()
    proc.stderr.close()
    assert proc.returncode in (0, -signal.SIGKILL), err
    return proc.returncode


def _one_line_refusal(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    return lines[0]


def _files(folder):
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _hidden(folder, name, patterns):
    """The hidden leftovers beside ``name``; each must be a staging name of ours (never mistakable for it)."""
    left = sorted(p.name for p in folder.iterdir() if p.name.startswith("."))
    for entry in left:
        assert any(re.fullmatch(pat.format(re.escape(name)), entry) for pat in patterns), entry
    return left


def _same_dataset(ds, ref):
    assert dict(ds.sizes) == dict(ref.sizes)
    for key in ref.data_vars:
        np.testing.assert_array_equal(np.asarray(ds[key].values), np.asarray(ref[key].values), err_msg=key)


def _whole_new_result(now):
    """``now`` is a finished run of paper.toml: its figures and identification (which the first result, written
    without figures, lacks) and a complete manifest."""
    return ("identification.json" in now and "figures/fig13_response.svg" in now
            and json.loads(now["manifest.json"])["complete"] is True)


@pytest.mark.slow
def test_killed_run_leaves_the_previous_complete_result(tmp_path):
    out = tmp_path / "out"
    push = load_case(EXAMPLES / "larger_push.toml")
    write_results(run_case(push, state_diagram=False), out, figures=False, report=False)
    previous = _files(out)
    outcomes = []

    def writing():  # the staging folder exists: the run is writing its files
        return any(p.name.startswith(".out.partial-") for p in tmp_path.iterdir())

    # once at a random moment, once at a random moment of the writing
    for delay, ready in ((RNG.uniform(0.5, 3.0), None), (RNG.uniform(0.0, 1.5), writing)):
        rc = _kill(_cmd("run", EXAMPLES / "paper.toml", "--out", out, "--overwrite"), delay, ready)
        now = _files(out)
        if rc == 0:  # finished before the kill: the whole new result, nothing of the old
            assert _whole_new_result(now)
            previous = now
        else:  # not one file changed, or killed after the new result was in place (while the process exited)
            assert now == previous or _whole_new_result(now)
        outcomes.append(rc)
        _hidden(tmp_path, "out", [r"\.{}\.partial-\d+", r"\.{}\.old-\d+"])
    # the next run into the folder clears what the killed ones left
    write_results(run_case(push, state_diagram=False), out, figures=False, report=False, overwrite=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"], outcomes


@pytest.mark.slow
@pytest.mark.parametrize("suffix", [".nc", pytest.param(".zarr", marks=pytest.mark.skipif(not HAS_ZARR,
                                                                                          reason="no zarr"))])
def test_killed_numpy_sweep_leaves_nothing_or_a_complete_file(tmp_path, suffix):
    import xarray as xr

    case = load_case(EXAMPLES / "larger_push.toml")
    out = tmp_path / f"s{suffix}"
    old_grids = {"F1": np.linspace(100.0, 900.0, 4), "F2": np.linspace(300.0, 1200.0, 3)}
    previous = sweep(case, old_grids, out=out)
    grids = {"F1": np.linspace(100.0, 900.0, 120), "F2": np.linspace(300.0, 1200.0, 50)}
    ref = sweep(case, grids)
    opener = xr.open_zarr if suffix == ".zarr" else xr.open_dataset

    def writing():  # a temporary file or staging folder beside --out: the store or file is being written
        return any(p.name.startswith(f".{out.name}.") for p in tmp_path.iterdir())

    rc = _kill(_cmd("sweep", EXAMPLES / "larger_push.toml", "--grid", "F1=100:900:120", "--grid", "F2=300:1200:50",
                    "--out", out, "--overwrite"), RNG.uniform(0.0, 0.2), writing)
    with opener(out) as ds:  # either the previous sweep or the new one, whole: never a mixture
        _same_dataset(ds.load(), ref if ds.sizes["F1"] == 120 else previous)
        assert rc != 0 or ds.sizes["F1"] == 120
    _hidden(tmp_path, out.name, [r"\.{}\.partial-\d+", r"\.{}\.old-\d+", r"\.{}\.\w+\.part",
                                 r"\.s_heatmaps\.(png|svg)\.\w+\.part"])


@pytest.mark.slow
@pytest.mark.skipif(not HAS_DASK, reason="dask/distributed/zarr not installed")
def test_killed_dask_sweep_resumes_to_the_identical_store(tmp_path):
    import xarray as xr

    case = load_case(EXAMPLES / "larger_push.toml")
    out = tmp_path / "s.zarr"
    staging = tmp_path / ".s.zarr.partial"
    grid = ["--grid", "F1=100:900:40", "--grid", "F2=300:1200:20"]
    base = _cmd("sweep", EXAMPLES / "larger_push.toml", *grid, "--out", out, "--backend", "dask", "--workers", 1,
                "--block-rows", 4)

    def some_blocks_done():
        done = staging / "_quickrelease_done"
        return done.is_dir() and any(p.name.isdigit() for p in done.iterdir())

    rc = _kill(base, RNG.uniform(0.0, 1.5), ready=some_blocks_done)
    # killed after the store was moved into place (while drawing the heat maps beside it), the store is the
    # complete result, checked below; killed before, nothing is at --out
    if rc != 0 and staging.exists():
        with pytest.raises(Exception):  # noqa: B017 - nothing at --out opens as a result
            xr.open_zarr(out)
        # resuming with a changed grid (a new shape; a new range: test_sweep.py) is refused in one line
        line = _one_line_refusal([c if c != "F1=100:900:40" else "F1=100:900:20" for c in base] + ["--resume"])
        assert "cannot resume" in line and "F1" in line, line
        assert not out.exists()
    r = subprocess.run(base + ["--resume"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    # the uninterrupted run computes the same blocks (a block's values can differ from a whole-grid numpy sweep
    # in the last bit: the vector kernels' rounding depends on the array shape)
    F1, F2 = np.linspace(100.0, 900.0, 40), np.linspace(300.0, 1200.0, 20)
    ref = xr.concat([sweep(case, {"F1": F1[i:i + 4], "F2": F2}) for i in range(0, 40, 4)], dim="F1")
    with xr.open_zarr(out) as ds:
        _same_dataset(ds.load(), ref)
    assert not staging.exists()


@pytest.mark.slow
def test_killed_uq_resumes_to_the_identical_result(tmp_path):
    case_path = tmp_path / "uq.toml"
    case_path.write_text(UQ_CASE)
    full = tmp_path / "full"
    run_uq(load_case(case_path), 60_000, seed=5, chunk=4_000, out=full, figures=False)
    out = tmp_path / "u"
    staging = tmp_path / ".u.partial"
    base = _cmd("uq", case_path, "--samples", 60_000, "--chunk", 4_000, "--seed", 5, "--out", out, "--json")
    rc = _kill(base, RNG.uniform(0.0, 0.6), ready=lambda: any((staging / "chunks").glob("chunk-*.npz")))
    if rc != 0:
        assert not out.exists()
        # a changed seed is refused (chunk size, samples, the case: test_runfolder.py)
        i = base.index("--seed")
        line = _one_line_refusal(base[:i + 1] + ["6"] + base[i + 2:] + ["--resume"])
        assert "cannot resume" in line and "seed" in line, line
    r = subprocess.run(base + ["--resume"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert (out / "uq.json").read_bytes() == (full / "uq.json").read_bytes()
    assert not staging.exists()


# -- issue 22: a full disk at a seeded point of the writing, and a closed standard output ---------------------

FULL_DISK_COMMANDS = {
    "run": ["run", EXAMPLES / "paper.toml", "--out", "{out}"],
    "uq": ["uq", "uq.toml", "--samples", "2000", "--chunk", "500", "--out", "{out}"],
    "sweep-nc": ["sweep", EXAMPLES / "larger_push.toml", "--grid", "F1=100:900:3", "--out", "{out}.nc"],
    "synth": ["synth", EXAMPLES / "paper.toml", "--channels", "u", "--rate", "200 Hz", "--out", "{out}.csv",
              "--case-out", "{out}.toml"],
}


#: How many files each writes through export.atomic_path (at least): k is drawn up to it, so every draw fails
#: at some write (uq: uq.json and the corner figure's two files; its chunks are counted apart).
FILES_WRITTEN = {"run": 8, "uq": 3, "sweep-nc": 3, "synth": 2}


@pytest.mark.slow
@pytest.mark.parametrize("command", list(FULL_DISK_COMMANDS))
@pytest.mark.parametrize("draw", range(3))
def test_a_full_disk_at_a_seeded_write_leaves_the_whole_result_or_nothing(tmp_path, monkeypatch, command, draw):
    """The disk fills at the k-th file written (k drawn from a seeded generator, the file's temporary already
    made) or at the final rename: the command ends in one line naming the output, exit 2, and leaves no
    staging folder, temporary file or partial output (uq's unfinished run included); or, when k is past its
    last write, it finishes whole."""
    import contextlib
    import errno

    from typer.testing import CliRunner

    from quickrelease.cli import app
    from quickrelease.io import export

    rng = random.Random(f"{command}-{draw}-20261126")
    k, at_rename = rng.randint(1, FILES_WRITTEN[command]), rng.random() < 0.3
    (tmp_path / "uq.toml").write_text(UQ_CASE)
    real_atomic, real_replace = export.atomic_path, os.replace
    count = [0]

    @contextlib.contextmanager
    def filling(path):
        with real_atomic(path) as tmp:
            count[0] += 1
            if count[0] == k and not at_rename:
                Path(tmp).write_bytes(b"the first bytes")
                raise OSError(errno.ENOSPC, "No space left on device")
            yield tmp

    def replace(src, dst, *args, **kwargs):
        count[0] += 1
        if at_rename and count[0] >= k:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_replace(src, dst, *args, **kwargs)

    monkeypatch.setattr(export, "atomic_path", filling)
    monkeypatch.setattr(os, "replace", replace)
    monkeypatch.chdir(tmp_path)
    args = [str(a).replace("{out}", "out") for a in FULL_DISK_COMMANDS[command]]
    r = CliRunner().invoke(app, args)
    monkeypatch.setattr(os, "replace", real_replace)
    left = sorted(p.name for p in tmp_path.iterdir() if p.name != "uq.toml")
    if r.exit_code == 0:  # k past the last write: the whole result
        assert left and not [n for n in left if n.startswith(".")], left
        return
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2 and len(lines) == 1 and "no space left" in lines[0] and "out" in lines[0], \
        (r.exit_code, r.stderr, r.exception)
    # what is left is whole (each file written through its own temporary file): the record before its case file
    # failed, the NetCDF file before its heat maps did
    assert left in ([], ["out.csv"], ["out.nc"]), left
    if left == ["out.csv"]:
        assert command == "synth" and (tmp_path / "out.csv").read_text().startswith("t_s,")
    if left == ["out.nc"]:
        import xarray as xr

        with xr.open_dataset(tmp_path / "out.nc") as ds:
            assert command == "sweep-nc" and ds.sizes["F1"] == 3 and np.isfinite(ds.stop_time.values).all()


@pytest.mark.slow
def test_json_to_a_closed_standard_output_is_one_line_after_a_whole_result(tmp_path):
    """--json into a pipe whose reader has gone: the files are whole (written before the JSON), then one line."""
    proc = subprocess.Popen(_cmd("synth", EXAMPLES / "paper.toml", "--channels", "u", "--rate", "200 Hz", "--out",
                                 tmp_path / "r.csv", "--json"), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    proc.stdout.close()
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 2 and err.count("\n") == 1 and "broken pipe" in err, err
    assert (tmp_path / "r.csv").read_text().startswith("t_s,")
