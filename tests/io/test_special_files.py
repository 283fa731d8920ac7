"""Issue 22, items 1-6 and 9: outputs never replace what is not a regular file the program may write, inputs
that are not regular files are refused before a byte is read, errors never quote a file's content, odd output
paths and write errors are one line, and the small ones (a building of 1e-300 kg, 5000 nested arrays, an
option given twice, ``--out ""``, an explicit step over the whole motion, rk at 1e27 J and more, the Zarr
warning, the note on rows without a time).

Device nodes and FIFOs are made in ``tmp_path`` (a character device with the null device's numbers, 1:3, made
there: never the machine's own /dev nodes); tests that need ``mknod`` of a device skip without root. Inputs
that would hang or read forever without the fix run in a subprocess with a timeout.
"""

from __future__ import annotations

import errno
import json
import math
import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from quickrelease.cli import app
from quickrelease.io import export
from quickrelease.io.runfolder import OutputError, RunFolder, staging_name

EXAMPLES = Path(__file__).parents[2] / "examples"
ROOT = hasattr(os, "geteuid") and os.geteuid() == 0
needs_root = pytest.mark.skipif(not ROOT, reason="mknod of a character device needs root")
SYNTH = ["synth", "case.toml", "--channels", "u", "--rate", "200 Hz"]
SWEEP = ["sweep", "case.toml", "--grid", "F1=100 N:900 N:2"]


def _cli(args, cwd):
    old = os.getcwd()
    os.chdir(cwd)
    try:
        r = CliRunner().invoke(app, [str(a) for a in args])
    finally:
        os.chdir(old)
    return r


def _one_line(r) -> str:
    assert r.exit_code == 2, (r.exit_code, r.stdout, r.stderr, r.exception)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in r.stderr, r.stderr
    return lines[0]


def _subprocess(args, cwd, **kwargs):
    return subprocess.run([sys.executable, "-m", "quickrelease.cli", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=60, env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)},
                          **kwargs)


def _one_line_sub(r) -> str:
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and lines[0].startswith("error: "), (r.returncode, r.stderr)
    return lines[0]


@pytest.fixture()
def work(tmp_path):
    shutil.copy(EXAMPLES / "paper.toml", tmp_path / "case.toml")
    shutil.copy(EXAMPLES / "fit.toml", tmp_path / "fit.toml")
    shutil.copytree(EXAMPLES / "records", tmp_path / "records")
    return tmp_path


def _node(path: Path, kind: str) -> None:
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "folder":
        path.mkdir()
    else:  # a character device with the numbers of the null (1:3) or zero (1:5) device, made here
        os.mknod(path, 0o666 | stat.S_IFCHR, os.makedev(1, {"chardev": 3, "zero": 5, "full": 7}[kind]))


def _is(path: Path, kind: str) -> bool:
    mode = os.lstat(path).st_mode
    return {"fifo": stat.S_ISFIFO, "folder": stat.S_ISDIR, "chardev": stat.S_ISCHR}[kind](mode)


def _hidden(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


# -- items 1 and 2: one rule for every output -------------------------------------------------------------------

KINDS = ["fifo", "folder", pytest.param("chardev", marks=needs_root)]
TARGETS = {  # command line with the target named "{}", and the target's name
    "synth --out": (SYNTH + ["--out", "{}"], "target.csv"),
    "synth --case-out": (SYNTH + ["--out", "r.csv", "--case-out", "{}"], "target.toml"),
    "sweep --out .nc": (SWEEP + ["--out", "{}"], "target.nc"),
}


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("target", list(TARGETS))
@pytest.mark.parametrize("overwrite", [False, True])
def test_a_special_file_as_output_is_never_replaced(work, target, kind, overwrite):
    """A device node, FIFO or folder where a file is to be written: one line, exit 2, still there as it was,
    nothing else written; --overwrite does not change that (a rename over a device node removes it)."""
    args, name = TARGETS[target]
    _node(work / name, kind)
    before = sorted(p.name for p in work.iterdir())
    line = _one_line(_cli([a.replace("{}", name) for a in args] + (["--overwrite"] if overwrite else []), work))
    assert name in line and ("not a regular file" in line or "is a folder" in line), line
    assert _is(work / name, kind)
    assert sorted(p.name for p in work.iterdir()) == before


@pytest.mark.parametrize("target", list(TARGETS))
def test_a_file_the_program_did_not_write_is_replaced_only_with_overwrite(work, target):
    args, name = TARGETS[target]
    (work / name).write_bytes(b"my own data\n")
    line = _one_line(_cli([a.replace("{}", name) for a in args], work))
    assert name in line and "--overwrite" in line, line
    assert (work / name).read_bytes() == b"my own data\n"
    assert not [p for p in work.iterdir() if p.name.startswith(("r.csv", "target_heatmaps"))]
    if target.startswith("synth"):  # (sweep --overwrite over a file: test_fault_injection.py)
        r = _cli([a.replace("{}", name) for a in args] + ["--overwrite"], work)
        assert r.exit_code == 0, r.stderr
        assert (work / name).read_bytes() != b"my own data\n"


def test_sweep_heat_maps_beside_a_new_file_are_not_replaced_without_overwrite(work):
    (work / "s_heatmaps.svg").write_text("my drawing")
    line = _one_line(_cli(SWEEP + ["--out", "s.nc"], work))
    assert "s_heatmaps.svg" in line
    assert (work / "s_heatmaps.svg").read_text() == "my drawing" and not (work / "s.nc").exists()


def test_the_same_file_twice_is_refused(work):
    line = _one_line(_cli(SYNTH + ["--out", "r.csv", "--case-out", "./r.csv"], work))
    assert "same file" in line


@pytest.mark.parametrize("kind", KINDS)
def test_atomic_path_never_renames_over_a_special_file(tmp_path, kind):
    """The library's one writer (every CSV, JSON, NetCDF, figure): a device node, FIFO or folder at the path
    raises OutputError, stays, and the temporary file is gone."""
    _node(tmp_path / "x.json", kind)
    with pytest.raises(OutputError, match="not a regular file"):
        export.write_json({"a": 1}, tmp_path / "x.json")
    assert _is(tmp_path / "x.json", kind) and _hidden(tmp_path) == []


# -- item 3: inputs that are not regular files -------------------------------------------------------------------

def _special_input_args(work: Path, role: str) -> list[str]:
    if role == "case":
        return ["simulate", "special", "--json"]
    if role == "device":
        (work / "c.toml").write_text((work / "case.toml").read_text().replace('preset = "paper"', 'file = "special"'))
        return ["simulate", "c.toml", "--f1", "420", "--f2", "800", "--json"]
    (work / "f.toml").write_text((work / "fit.toml").read_text().replace("records/paper_500Hz.csv", "special"))
    return ["fit", "f.toml"]


@pytest.mark.parametrize("role", ["case", "device", "record"])
def test_a_fifo_as_input_is_refused_at_once(work, role):
    """A FIFO named as the case file, the [device] file or the record (opening it would wait for a writer
    forever): one line "not a regular file" naming it, exit 2. Run in a thread that must end within a minute
    (without the check it never does)."""
    import threading

    _node(work / "special", "fifo")
    args = _special_input_args(work, role)
    box = []
    thread = threading.Thread(target=lambda: box.append(_cli(args, work)), daemon=True)
    thread.start()
    thread.join(60)
    if thread.is_alive():  # unblock the reader so the thread can end, then fail
        with open(work / "special", "w"):
            pass
        pytest.fail(f"{role}: waited on the FIFO")
    line = _one_line(box[0])
    assert "special: not a regular file (a FIFO)" in line, line


@pytest.mark.slow
@needs_root
def test_a_device_that_never_ends_as_a_record_is_refused_at_once(work):
    """A character device with the zero device's numbers (made here) as the record: one line, exit 2 (a
    subprocess with 2 GiB of memory and a timeout: without the check it reads until memory runs out)."""
    import resource

    _node(work / "special", "zero")
    args = _special_input_args(work, "record")

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (4 * 2**30, 4 * 2**30))

    line = _one_line_sub(_subprocess(args, work, preexec_fn=limit))
    assert "special: not a regular file (a character device)" in line, line


def test_an_input_over_the_size_cap_is_refused_with_its_size(work, monkeypatch):
    from quickrelease import _files

    monkeypatch.setattr(_files, "TOML_MAX_BYTES", 100)
    line = _one_line(_cli(["simulate", "case.toml", "--json"], work))
    assert "case.toml" in line and "over the" in line and "read at most" in line, line


def test_a_toml_of_5000_nested_arrays_is_one_line(work):
    (work / "n.toml").write_text("x = " + "[" * 5000 + "]" * 5000 + "\n")
    line = _one_line(_cli(["simulate", "n.toml"], work))
    assert "n.toml" in line and "nested" in line, line


# -- item 4: errors do not quote the content of the files they read ----------------------------------------------

@pytest.mark.parametrize("content", [
    "root:x:0:0:SECRET$6$hash:/root:/bin/bash\ndaemon:x:1:1:daemon:/usr/sbin:/usr/sbin/nologin\n",
    "t_s,SECRET:line:with:colons\n1,2\n",
    ",".join(f"c{k}" for k in range(3000)) + "\n" + ",".join("1" * 3000) + "\n",
])
def test_a_record_error_names_the_file_and_column_not_the_content(work, content):
    (work / "p.csv").write_text(content)
    (work / "f.toml").write_text((work / "fit.toml").read_text().replace("records/paper_500Hz.csv", "p.csv"))
    line = _one_line(_cli(["fit", "f.toml"], work))
    assert "p.csv" in line and ("'t_s'" in line or "'u_m'" in line), line
    assert "SECRET" not in line and "root" not in line and len(line) < 400, line


def test_columns_are_listed_from_a_header_that_parses_and_cut(work):
    (work / "p.csv").write_text(",".join(f"c{k}" for k in range(20)) + "\n" + ",".join("1" * 20) + "\n")
    (work / "f.toml").write_text((work / "fit.toml").read_text().replace("records/paper_500Hz.csv", "p.csv"))
    line = _one_line(_cli(["fit", "f.toml"], work))
    assert "(columns: c0, c1, " in line and "c7 and 12 more)" in line and "c8" not in line, line


def test_a_non_numeric_cell_is_described_not_quoted(work):
    text = (work / "records" / "paper_500Hz.csv").read_text().splitlines()
    cells = text[5].split(",")
    cells[1] = "my secret cell text that is long"
    text[5] = ",".join(cells)
    (work / "records" / "x.csv").write_text("\n".join(text) + "\n")
    (work / "f.toml").write_text((work / "fit.toml").read_text().replace("records/paper_500Hz.csv", "records/x.csv"))
    line = _one_line(_cli(["fit", "f.toml"], work))
    assert "row 5" in line and "secret" not in line and "a text of 32 characters" in line, line


# -- item 5: output paths ----------------------------------------------------------------------------------------

PATH_COMMANDS = {  # command -> (args with "{}" for the output, suffix)
    "run": (["run", "case.toml", "--out", "{}"], ""),
    "demo": (["demo", "--out", "{}"], ""),
    "uq": (["uq", "uq.toml", "--samples", "400", "--chunk", "200", "--out", "{}"], ""),
    "fit": (["fit", "fit.toml", "--out", "{}"], ""),
    "sweep": (SWEEP + ["--out", "{}"], ".nc"),
    "synth": (SYNTH + ["--out", "{}"], ".csv"),
}


@pytest.mark.parametrize("case", ["name over 255 bytes", "path over 4096 bytes", "under a file", "empty"])
@pytest.mark.parametrize("command", list(PATH_COMMANDS))
def test_an_impossible_output_path_is_one_line(work, command, case):
    shutil.copy(EXAMPLES / "uq_paper.toml", work / "uq.toml")
    args, suffix = PATH_COMMANDS[command]
    (work / "afile").write_text("x")
    out = {"name over 255 bytes": "n" * 300 + suffix, "path over 4096 bytes": "/".join(["p" * 200] * 21) + "/x" + suffix,
           "under a file": "afile/sub" + suffix, "empty": ""}[case]
    before = sorted(p.name for p in work.iterdir())
    line = _one_line(_cli([a.replace("{}", out) for a in args], work))
    assert {"name over 255 bytes": "over the 255", "path over 4096 bytes": "over the 4095",
            "under a file": "is a file, not a folder", "empty": "is empty"}[case] in line, line
    assert len(line) < 400 and sorted(p.name for p in work.iterdir()) == before


def test_staging_names_of_a_long_name_fit_the_file_system(tmp_path):
    name = "n" * 240  # legal; '.NAME.partial-PID' is not
    names = [staging_name(name, tag, tmp_path) for tag in ("partial", "partial-4194304", "partial-", "old-", "")]
    assert all(len(n.encode()) <= 255 - 13 for n in names)
    assert names[1].startswith(names[2]) and len({n.split("~")[0] for n in names}) == 1  # one cut for all
    assert staging_name("n" * 239, "x") != staging_name("n" * 240, "x")  # the hash keeps them apart
    assert staging_name("short", "partial-7") == ".short.partial-7"  # short names as before
    folder = RunFolder(tmp_path / name, "run", {"x": 1})
    with folder.staged() as w:
        (w / "a.json").write_text("{}")
    assert (tmp_path / name / "a.json").exists() and _hidden(tmp_path) == []


@pytest.mark.parametrize("command", ["synth", "sweep"])
def test_a_legal_240_character_name_is_written(work, command):
    args, suffix = PATH_COMMANDS[command]
    out = "n" * (240 - len(suffix)) + suffix
    r = _cli([a.replace("{}", out) for a in args], work)
    assert r.exit_code == 0, r.stderr
    assert (work / out).exists() and _hidden(work) == []


@pytest.mark.parametrize("error", [errno.EROFS, errno.ENOSPC])
def test_an_unwritable_folder_is_refused_before_the_work(work, monkeypatch, error):
    """A read-only mount (root writes anywhere else) or a full disk met by the pre-flight probe: one line."""
    import tempfile

    def refuse(*args, **kwargs):
        raise OSError(error, os.strerror(error))

    monkeypatch.setattr(tempfile, "mkstemp", refuse)
    for args, suffix in PATH_COMMANDS.values():
        if args[0] in ("uq", "demo"):
            continue
        line = _one_line(_cli([a.replace("{}", "o" + suffix) for a in args], work))
        assert {errno.EROFS: "read-only file system", errno.ENOSPC: "no space left"}[error] in line, line


def test_uq_on_a_full_disk_leaves_no_staging_folder(work, monkeypatch):
    from quickrelease.studies import uq

    shutil.copy(EXAMPLES / "uq_paper.toml", work / "uq.toml")

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(uq._ChunkStore, "save", full)
    line = _one_line(_cli(["uq", "uq.toml", "--samples", "400", "--chunk", "200", "--out", "u"], work))
    assert "no space left" in line and "u" in line
    assert not (work / "u").exists() and _hidden(work) == []


def test_a_write_error_without_a_file_name_names_the_file(work, monkeypatch):
    """A write on a full disk may raise an OSError without a file name: the message names --out, not the
    standard output, and nothing is left."""
    from quickrelease.studies import synth

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(synth, "open", full, raising=False)  # the CSV writer's open, inside atomic_path
    line = _one_line(_cli(SYNTH + ["--out", "r.csv"], work))
    assert "r.csv" in line and "no space left" in line and "standard output" not in line, line
    assert sorted(p.name for p in work.iterdir() if p.name.startswith((".", "r."))) == []


@pytest.mark.slow
def test_json_to_a_closed_pipe_is_one_line(work):
    p = subprocess.Popen([sys.executable, "-m", "quickrelease.cli", *SYNTH, "--out", "r.csv", "--json"], cwd=work,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    p.stdout.close()
    _, err = p.communicate(timeout=60)
    lines = err.strip().splitlines()
    assert p.returncode == 2 and len(lines) == 1 and "broken pipe" in lines[0], err


@pytest.mark.slow
@needs_root
def test_json_to_a_full_device_is_one_line(work):
    _node(work / "full", "full")  # the full device's numbers (1:7), made here
    with open(work / "full", "w") as out:
        r = subprocess.run([sys.executable, "-m", "quickrelease.cli", "simulate", "--energy", "2.9 kJ", "--alpha0",
                            "0.2", "--f1", "420", "--f2", "800", "--json"], cwd=work, stdout=out,
                           stderr=subprocess.PIPE, text=True, timeout=60,
                           env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and "no space left" in lines[0], r.stderr


def test_a_full_standard_output_in_process_is_one_line(work, monkeypatch):
    import typer

    echo = typer.echo

    def full(message=None, err=False, **kwargs):  # what click.echo raises on a full standard output
        if not err:
            raise OSError(errno.ENOSPC, "No space left on device")
        echo(message, err=err, **kwargs)

    monkeypatch.setattr(typer, "echo", full)
    r = _cli(["simulate", "--energy", "2.9 kJ", "--alpha0", "0.2", "--f1", "420", "--f2", "800", "--json"], work)
    assert "cannot write the standard output: no space left" in _one_line(r)


# -- item 6 ------------------------------------------------------------------------------------------------------

@pytest.mark.slow
def test_sweep_json_with_every_point_out_of_range_is_valid_json(work):
    """Pushes of 1e300 N store an E_S beyond the floats: every point flagged, its outputs NaN; the JSON has null."""
    shutil.copy(EXAMPLES / "larger_push.toml", work / "push.toml")
    shutil.copy(EXAMPLES / "device.toml", work / "device.toml")
    r = _cli(["sweep", "push.toml", "--grid", "force=1e300 N:1e301 N:3", "--out", "s.nc", "--json"], work)
    assert r.exit_code == 0, r.stderr
    data = json.loads(r.stdout, parse_constant=lambda c: pytest.fail(f"{c} in JSON"))
    assert data["flagged"] == 3 and data["stop_time_s"] == [None, None] and data["u_final_m"] == [None, None]


@pytest.mark.parametrize("rows", ["5", "1000000000000", "9223372036854775808"])
def test_dask_block_rows_beyond_the_grid_is_one_line(work, rows):
    pytest.importorskip("dask")
    pytest.importorskip("zarr")
    line = _one_line(_cli(SWEEP[:-1] + ["F1=100 N:900 N:4", "--out", "s.zarr", "--backend", "dask",
                                        "--block-rows", rows], work))
    assert "--block-rows" in line and "[1, 4]" in line
    assert not (work / "s.zarr").exists() and _hidden(work) == []


# -- item 9: the small ones --------------------------------------------------------------------------------------

BUILDING = """[building]
mass = "{mass}"
period = "2.0 s"
damping_ratio = 0.05
friction_coefficient = 0.02
displacement = "0.15 m"
"""


@pytest.mark.parametrize("mass", ["1e-300 kg", "0.5 kg", "1e13 kg"])
def test_a_building_mass_outside_the_sane_range_is_one_line(work, mass):
    (work / "b.toml").write_text(BUILDING.format(mass=mass))
    line = _one_line(_cli(["synth", "b.toml", "--out", "b.csv", "--duration", "5 s"], work))
    assert "[building] mass" in line and "[1, 1e+12] kg" in line, line


def test_a_building_of_one_kilogram_is_accepted(work):
    """The bound's edge: 1 kg simulates (k m = 1e1 N/m kg, far from underflow)."""
    (work / "b.toml").write_text(BUILDING.format(mass="1 kg"))
    r = _cli(["synth", "b.toml", "--out", "b.csv", "--duration", "5 s", "--json"], work)
    assert r.exit_code == 0, r.stderr


@pytest.mark.parametrize("args,words", [
    (SWEEP + ["--grid", "F1=200 N:300 N:2", "--out", "s.nc"], "F1 is given twice"),
    (SYNTH + ["--noise", "u=1 mm,u=2 mm", "--out", "n.csv"], "channel u is given twice"),
    (SYNTH + ["--noise", "u=1 mm", "--noise", "u=2 mm", "--out", "n.csv"], "channel u is given twice"),
    (SYNTH + ["--offset", "u=1 mm,u=2 mm", "--out", "n.csv"], "channel u is given twice"),
    (["run", "case.toml", "--out", ""], "--out is empty"),
    (["run", "case.toml", "--out="], "--out is empty"),
    (SYNTH + ["--out", " "], "--out is empty"),
])
def test_an_option_given_twice_or_empty_is_refused(work, args, words):
    before = sorted(p.name for p in work.iterdir())
    assert words in _one_line(_cli(args, work))
    assert sorted(p.name for p in work.iterdir()) == before


def test_an_explicit_step_over_the_motion_is_refused(work):
    line = _one_line(_cli(["simulate", "--energy", "2.9 kJ", "--alpha0", "0.2", "--f1", "420", "--f2", "805",
                           "--method", "explicit", "--dt", "1e308", "--json"], work))
    assert "dt = 1e+308 s" in line and "at least 10 steps" in line, line


def test_the_explicit_step_bound_is_a_tenth_of_the_stop_time():
    from quickrelease import simulate

    t_F = simulate(2900.0, 0.2, 420.0, 805.0).stop_time
    simulate(2900.0, 0.2, 420.0, 805.0, method="explicit", dt=t_F / 10.5)  # accepted
    with pytest.raises(ValueError, match="at least 10 steps"):
        simulate(2900.0, 0.2, 420.0, 805.0, method="explicit", dt=t_F / 9.5)


def _t_F_mpmath(E, a0, F1, F2, m1, m2, L1, c):
    """t_F = int dalpha / alpha_dot with alpha_dot^2 = (E - W_F(alpha)) / (m2 L1^2 (c m1/m2 + sin^2 alpha)) (the
    energy balance, Eq. 6-7), up to the stop (alpha_dot = 0) or pi/2, in 40 digits."""
    import mpmath as mp

    mp.mp.dps = 40
    E, a0, F1, F2, m1, m2, L1, c = map(mp.mpf, (E, a0, F1, F2, m1, m2, L1, c))
    k = c * m1 / m2

    def K(a):  # kinetic energy left
        return E - (2 * F1 * L1 * (mp.sin(a) - mp.sin(a0)) + 4 * F2 * L1 * (mp.cos(a0) - mp.cos(a)))

    end = mp.pi / 2 if K(mp.pi / 2) > 0 else mp.findroot(K, (a0, mp.pi / 2), solver="anderson")
    return mp.quad(lambda a: mp.sqrt(m2 * L1 ** 2 * (k + mp.sin(a) ** 2) / K(a)), [a0, end])


@pytest.mark.parametrize("E", [1e27, 1e30, 1e35, 1e100])
@pytest.mark.parametrize("a0", [0.05, 1.0, 1.5])
def test_rk_at_huge_energies_agrees_with_the_energy_balance(E, a0):
    """rk located its events to an absolute 4 eps in seconds: t_F of 1e-12 s came out 1e-5 to 1e-2 off, and 0
    at 1e35 J. Against the energy balance integrated in 40 digits (written here)."""
    from quickrelease import simulate
    from quickrelease.device.parameters import preset

    d = preset("paper")
    r = simulate(E, a0, 420.0, 805.0, method="rk", mass_model="distributed")
    ref = float(_t_F_mpmath(E, a0, 420.0, 805.0, d.m1, d.m2, d.L1, 2.0 / 3.0))
    assert r.stop_time > 0 and r.stop_time == pytest.approx(ref, rel=1e-8)


def test_rk_at_the_paper_case_agrees_with_the_energy_balance():
    from quickrelease import simulate
    from quickrelease.device.parameters import preset

    d = preset("paper")
    r = simulate(2900.0, 0.2, 420.0, 805.0, method="rk", mass_model="distributed")
    assert r.stop_time == pytest.approx(float(_t_F_mpmath(2900.0, 0.2, 420.0, 805.0, d.m1, d.m2, d.L1, 2 / 3)),
                                        rel=1e-9)


def test_rows_without_a_time_are_noted_by_run_and_fit(work):
    """The docs promise a note for rows without a time; ``fit`` printed it, ``run`` of the same case did not."""
    from quickrelease import cli
    from quickrelease.io.case import load_case
    from quickrelease.studies.fit import fit_record

    text = (work / "records" / "paper_500Hz.csv").read_text().splitlines()
    text = text[:1] + text[1::4]  # 125 Hz: a fast fit
    for i in (5, 6, 7):
        text[i] = "," + text[i].split(",", 1)[1]
    (work / "records" / "n.csv").write_text("\n".join(text) + "\n")
    (work / "f.toml").write_text((work / "fit.toml").read_text().replace("records/paper_500Hz.csv", "records/n.csv")
                                 .replace("a_head = {", "# a_head = {"))
    fit = fit_record(load_case(work / "f.toml"))
    assert "n.csv: 3 row(s) without a time value dropped" in fit.notes

    class Result:  # what run_case returns, as far as run reads it after writing
        pass

    lines = []
    import typer

    original = typer.echo
    try:
        typer.echo = lambda message="", err=False, **k: lines.append((message, err))
        cli._record_notes(fit)
        cli._record_notes(fit, err=True)
    finally:
        typer.echo = original
    assert ("note: n.csv: 3 row(s) without a time value dropped", False) in lines
    assert ("note: n.csv: 3 row(s) without a time value dropped", True) in lines
    source = Path(cli.__file__).read_text()  # run calls it with the fit of its result
    assert "_record_notes(result.fit, err=as_json)" in source


def test_a_zarr_sweep_gives_no_zarr_warning(work):
    """Zarr 3 warned (two lines on stderr) about consolidated metadata on every Zarr sweep."""
    pytest.importorskip("zarr")
    import warnings

    from quickrelease.io.case import load_case
    from quickrelease.studies.sweep import sweep

    case = load_case(work / "case.toml")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ds = sweep(case, {"F1": np.array([100.0, 900.0])}, out=work / "s.zarr")
    assert not [w for w in caught if "onsolidated" in str(w.message)], [str(w.message) for w in caught]
    assert math.isfinite(float(ds.stop_time.min()))
