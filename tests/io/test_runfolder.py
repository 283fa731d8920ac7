"""Output folders that never lie (issue 9, items 1, 3, 4, 5): fingerprints refuse a resume with other inputs,
a resume computes only what is missing, damaged chunks and manifests are named and recomputed, a folder holds
exactly one run, and every output-path problem is one line with nothing half-written."""

import errno
import json
import os
from pathlib import Path

import pytest
from conftest import UQ_CASE
from typer.testing import CliRunner

from quickrelease.cli import app
from quickrelease.io.case import load_case
from quickrelease.io.runfolder import OutputError
from quickrelease.studies import uq as uq_module
from quickrelease.studies.uq import run_uq
from quickrelease.workflow import run_case, write_results

EXAMPLES = Path(__file__).parents[2] / "examples"
SAMPLES, CHUNK, SEED = 2000, 500, 3  # four chunks


class Killed(BaseException):
    """Stands for a kill: not an Exception, so nothing on the way catches it."""


@pytest.fixture()
def case_path(tmp_path):
    path = tmp_path / "uq.toml"
    path.write_text(UQ_CASE)
    return path


@pytest.fixture()
def spy(monkeypatch):
    """Counts the uq chunks computed; ``spy.kill_after = n`` interrupts the run after n chunks."""

    class Spy:
        calls: list[int] = []
        kill_after: int | None = None

    real = uq_module.uq_chunk

    def counted(case, seed, index, size, edges, *more, **options):
        if Spy.kill_after is not None and len(Spy.calls) >= Spy.kill_after:
            raise Killed
        Spy.calls.append(index)
        return real(case, seed, index, size, edges, *more, **options)

    Spy.calls = []
    monkeypatch.setattr(uq_module, "uq_chunk", counted)
    return Spy


def _interrupted(case_path, out, spy, after=2):
    spy.kill_after, spy.calls[:] = after, []
    with pytest.raises(Killed):
        run_uq(load_case(case_path), SAMPLES, seed=SEED, chunk=CHUNK, out=out, figures=False)
    spy.kill_after, spy.calls[:] = None, []
    staging = out.with_name(f".{out.name}.partial")
    assert not out.exists() and len(list((staging / "chunks").glob("chunk-*.npz"))) == after
    return staging


def _cli(args):
    r = CliRunner().invoke(app, [str(a) for a in args])
    return r.exit_code, r.stdout, r.stderr


def _one_line_error(code, stderr):
    assert code == 2, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in stderr, stderr
    return lines[0]


def _uq_args(case_path, out, *extra, seed=SEED, chunk=CHUNK, samples=SAMPLES):
    return ["uq", case_path, "--samples", samples, "--chunk", chunk, "--seed", seed, "--out", out, "--json", *extra]


@pytest.fixture()
def uninterrupted(case_path, tmp_path):
    full = tmp_path / "full"
    run_uq(load_case(case_path), SAMPLES, seed=SEED, chunk=CHUNK, out=full, figures=False)
    return (full / "uq.json").read_bytes()


def test_uq_resume_computes_only_the_missing_chunks(case_path, tmp_path, spy, uninterrupted):
    out = tmp_path / "part"
    _interrupted(case_path, out, spy, after=2)
    run_uq(load_case(case_path), SAMPLES, seed=SEED, chunk=CHUNK, out=out, resume=True, figures=False)
    assert sorted(spy.calls) == [2, 3]  # the two finished chunks are not computed again
    assert (out / "uq.json").read_bytes() == uninterrupted
    assert not out.with_name(".part.partial").exists()
    # resuming a finished run computes nothing and changes nothing
    spy.calls[:] = []
    run_uq(load_case(case_path), SAMPLES, seed=SEED, chunk=CHUNK, out=out, resume=True, figures=False)
    assert spy.calls == [] and (out / "uq.json").read_bytes() == uninterrupted


@pytest.mark.parametrize("change", ["seed", "chunk", "samples", "case"])
def test_uq_resume_with_other_inputs_is_refused(case_path, tmp_path, spy, change):
    out = tmp_path / "part"
    staging = _interrupted(case_path, out, spy)
    before = {p.name: p.read_bytes() for p in (staging / "chunks").iterdir()}
    kw = {"seed": SEED, "chunk": CHUNK, "samples": SAMPLES}
    if change == "case":  # the observation's std edited (issue 9, item 1: gave a mixed std F1 before)
        case_path.write_text(UQ_CASE.replace('std = "0.01 rad"', 'std = "0.02 rad"'))
    else:
        kw[change] += {"seed": 1, "chunk": 250, "samples": 500}[change]
    code, _, err = _cli(_uq_args(case_path, out, "--resume", **kw))
    line = _one_line_error(code, err)
    assert "cannot resume" in line and {"seed": "seed", "chunk": "chunk", "samples": "samples",
                                        "case": "alpha_final"}[change] in line, line
    assert spy.calls == [] and not out.exists()  # nothing computed, the unfinished run untouched
    assert {p.name: p.read_bytes() for p in (staging / "chunks").iterdir()} == before


def test_resuming_a_finished_run_with_other_inputs_is_refused(case_path, tmp_path, spy, uninterrupted):
    out = tmp_path / "full"  # the finished run of the fixture
    spy.calls[:] = []
    line = _one_line_error(*_cli(_uq_args(case_path, out, "--resume", seed=SEED + 1))[::2])
    assert "cannot resume" in line and "seed" in line
    assert spy.calls == [] and (out / "uq.json").read_bytes() == uninterrupted
    line = _one_line_error(*_cli(_uq_args(case_path, out, seed=SEED + 1))[::2])
    assert "another run" in line and "--overwrite" in line


def test_uq_unfinished_run_needs_resume_or_overwrite(case_path, tmp_path, spy, uninterrupted):
    out = tmp_path / "part"
    _interrupted(case_path, out, spy)
    line = _one_line_error(*_cli(_uq_args(case_path, out))[::2])
    assert "pass --resume" in line and "--overwrite" in line
    code, _, err = _cli(_uq_args(case_path, out, "--overwrite"))
    assert code == 0, err
    assert sorted(spy.calls) == [0, 1, 2, 3]  # started again
    assert json.loads((out / "uq.json").read_bytes()) == json.loads(uninterrupted)


@pytest.mark.slow
def test_truncated_chunk_is_named_and_recomputed(case_path, tmp_path, spy, uninterrupted):
    out = tmp_path / "part"
    staging = _interrupted(case_path, out, spy, after=3)
    damaged = staging / "chunks" / "chunk-000001.npz"
    damaged.write_bytes(damaged.read_bytes()[: damaged.stat().st_size // 2])
    code, stdout, err = _cli(_uq_args(case_path, out, "--resume"))
    assert code == 0 and "Traceback" not in err, err
    notes = [line for line in err.splitlines() if line.startswith("note: ")]
    assert len(notes) == 1 and "chunk-000001.npz" in notes[0] and "recomput" in notes[0], err
    assert sorted(spy.calls) == [1, 3]
    assert (out / "uq.json").read_bytes() == uninterrupted


def test_chunk_of_another_run_is_recomputed(case_path, tmp_path, spy, uninterrupted):
    """A chunk file carries the fingerprint: one copied from a run with another seed is not mixed in."""
    other = tmp_path / "other"
    _interrupted(case_path, other, spy, after=1)
    spy.kill_after = None
    out = tmp_path / "part"
    staging = _interrupted(case_path, out, spy, after=2)
    (other.with_name(".other.partial") / "chunks" / "chunk-000000.npz").replace(staging / "chunks" / "chunk-000000.npz")
    # same seed here, so make the stranger really another run's: rewrite its fingerprint
    import numpy as np

    path = staging / "chunks" / "chunk-000000.npz"
    with np.load(path) as z:
        part = {k: z[k] for k in z.files}
    part["fingerprint"] = np.array("0" * 64)
    with open(path, "wb") as fh:
        np.savez(fh, **part)
    code, _, err = _cli(_uq_args(case_path, out, "--resume"))
    assert code == 0, err
    assert "chunk-000000.npz" in err and "other inputs" in err
    assert sorted(spy.calls) == [0, 2, 3]
    assert (out / "uq.json").read_bytes() == uninterrupted


@pytest.mark.slow
def test_corrupt_manifest_is_named_and_the_run_resumed(case_path, tmp_path, spy, uninterrupted):
    out = tmp_path / "part"
    staging = _interrupted(case_path, out, spy)
    (staging / "manifest.json").write_text('{"format": "quickrelease-run/1", "fingerp')  # cut by a kill
    line = _one_line_error(*_cli(_uq_args(case_path, out))[::2])
    assert "manifest.json" in line and "damaged" in line and "--resume" in line
    code, _, err = _cli(_uq_args(case_path, out, "--resume"))
    assert code == 0 and "Traceback" not in err, err
    assert "manifest.json" in err  # named in a note
    assert sorted(spy.calls) == [2, 3]  # the chunks carry the fingerprint: still this run's, kept
    assert (out / "uq.json").read_bytes() == uninterrupted


def test_corrupt_manifest_of_a_finished_folder_is_one_line(case_path, tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    (out / "manifest.json").write_bytes(b"\x00\xff garbage")
    line = _one_line_error(*_cli(_uq_args(case_path, out))[::2])
    assert "manifest.json" in line and "--overwrite" in line


# -- item 4: a folder holds exactly one run -------------------------------------------------------------------

def _files(folder):
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_another_case_into_the_same_folder(tmp_path):
    out = tmp_path / "out"
    paper, push = load_case(EXAMPLES / "paper.toml"), load_case(EXAMPLES / "larger_push.toml")
    write_results(run_case(paper, state_diagram=False), out, figures=False, report=False)
    first = _files(out)
    assert "identification.json" in first
    # the CLI refuses before any work, in one line, and leaves the folder as it was
    line = _one_line_error(*_cli(["run", EXAMPLES / "larger_push.toml", "--out", out])[::2])
    assert "another run" in line and "--overwrite" in line
    assert _files(out) == first
    with pytest.raises(OutputError, match="another run"):
        write_results(run_case(push, state_diagram=False), out, figures=False, report=False)
    # with overwrite: exactly what that run writes, as in a fresh folder (no stale identification.json)
    write_results(run_case(push, state_diagram=False), out, figures=False, report=False, overwrite=True)
    fresh = tmp_path / "fresh"
    write_results(run_case(push, state_diagram=False), fresh, figures=False, report=False)
    assert sorted(_files(out)) == sorted(_files(fresh)) and "identification.json" not in _files(out)
    assert _files(out)["summary.json"] == _files(fresh)["summary.json"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fresh", "out"]  # no staging folder left


def test_a_folder_of_someone_elses_files_is_not_replaced(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "thesis.tex").write_text("years of work")
    push = load_case(EXAMPLES / "larger_push.toml")
    for overwrite in (False, True):
        with pytest.raises(OutputError, match="did not write"):
            write_results(run_case(push, state_diagram=False), out, figures=False, report=False,
                          overwrite=overwrite)
    assert _files(out) == {"thesis.tex": b"years of work"}


# -- item 5: output paths --------------------------------------------------------------------------------------

def _unwritable(tmp_path):
    if os.geteuid() != 0:
        folder = tmp_path / "ro"
        folder.mkdir()
        folder.chmod(0o500)
        return folder
    return Path("/proc")  # root writes anywhere chmod allows; nobody creates files in /proc


@pytest.mark.parametrize("where", ["existing file", "under a file", "unwritable"])
@pytest.mark.parametrize("command", ["run", "uq", "sweep-zarr", "sweep-nc"])
def test_bad_out_is_one_line_and_nothing_is_written(tmp_path, case_path, where, command, monkeypatch):
    blocker = tmp_path / "blocker.txt"
    blocker.write_text("a file")
    suffix = {"sweep-zarr": ".zarr", "sweep-nc": ".nc"}.get(command, "")
    if where == "existing file":
        out = blocker
        if command == "sweep-nc":  # a folder where a file is expected
            out = tmp_path / "folder.nc"
            out.mkdir()
    elif where == "under a file":
        out = blocker / f"sub{suffix}"
    else:
        out = _unwritable(tmp_path) / f"out{suffix}"
    args = {"run": ["run", EXAMPLES / "paper.toml", "--out", out],
            "uq": _uq_args(case_path, out),
            "sweep-zarr": ["sweep", EXAMPLES / "larger_push.toml", "--grid", "F1=100:200:3", "--out", out],
            "sweep-nc": ["sweep", EXAMPLES / "larger_push.toml", "--grid", "F1=100:200:3", "--out", out]}[command]
    from quickrelease import workflow

    work = []
    real = workflow.run_case
    monkeypatch.setattr(workflow, "run_case", lambda *a, **k: work.append(1) or real(*a, **k))
    before = sorted(p.name for p in tmp_path.iterdir())
    line = _one_line_error(*_cli(args)[::2])
    assert str(out) in line or out.name in line, line
    assert work == []  # refused before the work (pre-flight)
    assert sorted(p.name for p in tmp_path.iterdir()) == before and blocker.read_text() == "a file"


def test_full_disk_midway_leaves_the_previous_complete_result(tmp_path, monkeypatch):
    out = tmp_path / "out"
    paper = load_case(EXAMPLES / "paper.toml")
    result = run_case(paper, state_diagram=False)
    write_results(result, out, figures=False, report=False)
    first = _files(out)
    from quickrelease.io import export

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(export, "write_netcdf", full)  # after summary.json, identification.json, the CSV
    with pytest.raises(OutputError, match="no space left") as info:
        write_results(result, out, figures=False, report=False, overwrite=True)
    assert "\n" not in str(info.value)
    assert _files(out) == first
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # the staging folder is gone
    # with no previous result: nothing at all
    with pytest.raises(OutputError, match="no space left"):
        write_results(result, tmp_path / "new", figures=False, report=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def test_full_disk_through_the_cli_is_one_line(tmp_path, monkeypatch):
    import xarray as xr

    def full(self, path, *args, **kwargs):
        Path(path).write_bytes(b"CDF\x01 the first bytes")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", full)
    out = tmp_path / "out.nc"
    line = _one_line_error(*_cli(["sweep", EXAMPLES / "larger_push.toml", "--grid", "F1=100:200:3",
                                  "--out", out])[::2])
    assert "no space left" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_the_digest_of_a_fifo_or_a_device_node_is_none_at_once(tmp_path):
    """A campaign's record that is a FIFO (made here) blocked `quickrelease campaign` for ever: the run folder's
    fingerprint read it, waiting for a writer, before the records' reader could refuse it in one line. The digest
    of what is no regular file is None (the reader then says what it is); a regular file's is its SHA-256."""
    import hashlib
    import os
    import stat
    import threading

    from quickrelease.io.runfolder import _file_digest

    fifo, node, regular = tmp_path / "r.csv", tmp_path / "n.csv", tmp_path / "ok.csv"
    os.mkfifo(fifo)
    try:
        os.mknod(node, 0o600 | stat.S_IFCHR, os.makedev(1, 3))  # a node like /dev/null, in the test's own folder
    except PermissionError:  # not root: a second FIFO in its place
        os.mkfifo(node)
    regular.write_bytes(b"t_s,x_mm\n0,1\n" * 100_000)
    got = {}
    worker = threading.Thread(target=lambda: got.update(fifo=_file_digest(fifo), node=_file_digest(node)), daemon=True)
    worker.start()
    worker.join(10.0)
    if worker.is_alive():  # blocked in open(): let it go (a writer that closes at once), then fail
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        pytest.fail("the digest of a FIFO waited for a writer")
    assert got == {"fifo": None, "node": None}
    assert _file_digest(regular) == hashlib.sha256(regular.read_bytes()).hexdigest()
    assert _file_digest(tmp_path / "missing.csv") is None
