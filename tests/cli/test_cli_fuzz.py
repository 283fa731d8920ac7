"""CLI fuzz test: bad values for every option of every command, as an adversarial user would type them.

The options come from the Typer app itself (click introspection), so a new option is fuzzed without
editing this file: a string option is taken as a quantity (or a word), an int or float option as a
number. Every invocation runs in a fresh temporary working folder and must end in one of two ways:

* refused: exit code 2, exactly one line on stderr starting with ``error: ``, no traceback, and no
  file left behind (the folder holds what it held before);
* accepted (only for values that may be legitimate for some options, such as 0, -1, 1e-308): exit 0,
  and the JSON printed has no NaN or infinity.

Values that are never legitimate (NaN, infinity, empty, a bare unit, a power tower, a 10k-character
string, a wrong dimension, text) must be refused. The sample is seeded: a fixed list per value class,
plus a few random numbers with random units per option.
"""

from __future__ import annotations

import json
import os
import random
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from unittest import mock

import pytest
import typer
from typer.testing import CliRunner

from quickrelease.cli import app

pytestmark = pytest.mark.slow  # the default run skips it; `-m slow` or CI runs it

#: The click command of the app, built once: Typer rebuilds it on every ``CliRunner.invoke`` (about 0.1 s,
#: most of the time of a refused value).
COMMAND = typer.main.get_command(app)


class _Runner(CliRunner):
    """Typer's CliRunner on the prebuilt command (stdout and stderr kept apart, as the click in use does)."""

    def invoke(self, app_, args=None, **kwargs):
        with mock.patch("typer.testing._get_command", lambda _: COMMAND):
            return super().invoke(app_, args, **kwargs)


runner = _Runner()

#: Never-legitimate values of a quantity option: class -> value.
ALWAYS_BAD = {
    "nan": "nan", "inf": "inf", "-inf": "-inf", "nan with unit": "nan kN", "inf with unit": "inf s",
    "empty": "", "blank": "   ", "bare unit": "kN", "bare unit 2": "deg", "power tower": "9**9**9",
    "expression": "2*3 kN", "10k characters": "1" * 10_000, "10k of unit": "1 " + "k" * 10_000,
    "overflow literal": "1e99999", "non-ASCII": "Prüfung", "escape sequence": "\x1b[31m1\x1b]0;x\x07",
    "wrong dimension": "3 kg/m^3", "unknown unit": "3 blorps", "two numbers": "1 2",
}
#: Values that some options accept (a friction of 0, a seed of 0) and others refuse.
MAYBE_BAD = {"-1": "-1", "0": "0", "-0": "-0", "1e308": "1e308", "1e-308": "1e-308", "5e-324": "5e-324",
             "huge int": "99999999999999999999999", "negative int": "-7"}
#: Never-legitimate values of an integer option (Typer's parser or ours).
INT_ALWAYS_BAD = {"float": "1.5", "exponent": "1e23", "nan": "nan", "empty": "", "text": "Prüfung",
                  "huge int": "10" + "0" * 30}
INT_MAYBE_BAD = {"-1": "-1", "0": "0", "negative": "-999999999999", "big": "100000"}


def _data(name: str) -> Path:
    return Path(str(resources.files("quickrelease") / "data" / "cases" / name))


@dataclass(frozen=True)
class Command:
    """A cheap valid invocation and how to put a value into each option."""

    args: tuple[str, ...]
    #: option -> template of the bad value ("{}" is the value); default "{}"
    templates: dict[str, str]
    #: options that take any string (paths, addresses): not fuzzed here
    skip: tuple[str, ...] = ()
    #: options that are inert in the baseline (fuzzed, but a value may be accepted)
    lenient: tuple[str, ...] = ()
    #: option -> baseline options to drop (with their value) and arguments to add when fuzzing it
    swap: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = field(default_factory=dict)
    #: option -> value classes left out (legitimate and slow: 100,000 uq samples)
    slow: dict[str, tuple[str, ...]] = field(default_factory=dict)
    #: the command to invoke when the key names a variant (e.g. "synth-building": synth of a building case)
    command: str | None = None


#: Commands with options to fuzz; cheap baselines (each runs in well under a second when accepted).
COMMANDS: dict[str, Command] = {
    "simulate": Command(("--energy", "2.9 kJ", "--alpha0", "0.2", "--f1", "420", "--f2", "800", "--json"), {},
                        swap={"--force": (("--energy",), ()), "--dt": ((), ("--method", "explicit"))}),
    "identify": Command(("--energy", "2.9 kJ", "--alpha0", "0.2", "--alpha-final", "0.7378", "--stop-time", "1.05",
                         "--json"), {}, swap={"--force": (("--energy",), ())}),
    "uq": Command(("{uq_case}", "--samples", "400", "--chunk", "200", "--json"), {}, skip=("--scheduler",),
                  slow={"--samples": ("big",)}),
    "sweep": Command(("{case}", "--grid", "force=1000 kN:2000 kN:2", "--out", "sweep.nc", "--json"),
                     {"--grid": "force={}:2000 kN:3"}, skip=("--scheduler",), lenient=("--workers",)),
    "synth": Command(("{case}", "--out", "record.csv", "--channels", "u", "--rate", "200 Hz", "--json"),
                     {"--noise": "u={}", "--offset": "u={}"}),
    "synth-building": Command(("{building_case}", "--out", "record.csv", "--channels", "x", "--duration", "5 s",
                               "--json"), {"--noise": "x={}", "--offset": "x={}"}, command="synth",
                               skip=("--seed", "--jitter", "--missing")),  # checked as for the device (above)
    "demo": Command(("--out", "demo",), {}),
    "plan": Command(("{case}", "--json"), {}),
    "bench": Command(("--quick", "--json"), {}),  # --threads is its only value option: every value fuzzed is refused
    "building": Command(("{building_case}", "--json"), {}),  # --model is checked before the case is read
}

#: A case of the building alone (synth-building's baseline).
BUILDING_CASE = """[building]
mass = "650 t"
period = "2.0 s"
damping_ratio = 0.05
friction_coefficient = 0.02
displacement = "0.15 m"
"""


def _kind(param) -> str | None:
    """'int', 'float' or 'str' for an option that takes a value; None for flags, paths and arguments."""
    if not param.opts[0].startswith("-") or getattr(param, "is_flag", False):
        return None
    descriptor = getattr(param, "type_descriptor", None)  # Typer >= 0.25 (its own click)
    annotation = descriptor.annotation if descriptor is not None else None
    if annotation is None:  # Typer on click: the click type's name
        annotation = {"integer": int, "float": float, "text": str}.get(getattr(param.type, "name", ""), Path)
    annotation = getattr(annotation, "__args__", (annotation,))[0] if annotation not in (int, float, str) else \
        annotation  # list[str] (repeatable options) -> str
    return {int: "int", float: "float", str: "str"}.get(annotation)


def _options(command: str):
    """(option name, 'int' | 'float' | 'str') for every fuzzable option of the command, from the app.

    Flags and paths are left to the other tests (the output-path tests cover paths)."""
    cmd = COMMAND.commands[COMMANDS[command].command or command]
    for p in cmd.params:
        kind = _kind(p)
        name = max(p.opts, key=len)
        if kind is None or name in COMMANDS[command].skip:
            continue
        yield name, kind


def _cases():
    rng = random.Random(20240917)
    units = ["N", "kN", "MN", "J", "kJ", "rad", "deg", "s", "ms", "Hz", "m", "mm", "kg", "m/s^2", "", "furlong"]
    out = []
    for command in COMMANDS:
        for option, kind in _options(command):
            if kind == "int":
                classes = [(c, v, True) for c, v in INT_ALWAYS_BAD.items()]
                classes += [(c, v, False) for c, v in INT_MAYBE_BAD.items()]
            else:
                classes = [(c, v, True) for c, v in ALWAYS_BAD.items()]
                classes += [(c, v, False) for c, v in MAYBE_BAD.items()]
                for _ in range(2):  # seeded random numbers with random units
                    value = f"{rng.choice(['-', ''])}{10 ** rng.uniform(-320, 320):.3g} {rng.choice(units)}".strip()
                    classes.append(("random", value, False))
            for cls, value, strict in classes:
                if cls in COMMANDS[command].slow.get(option, ()):
                    continue
                strict = strict and option not in COMMANDS[command].lenient
                out.append(pytest.param(command, option, cls, value, strict, id=f"{command}-{option}-{cls}"))
    return out


def _invoke(command: str, option: str, value: str, cwd: Path):
    spec = COMMANDS[command]
    shutil.copy(_data("paper.toml"), cwd / "case.toml")
    shutil.copy(_data("uq_paper.toml"), cwd / "uq.toml")
    (cwd / "building.toml").write_text(BUILDING_CASE)
    base = [a.format(case="case.toml", uq_case="uq.toml", building_case="building.toml") for a in spec.args]
    drop, add = spec.swap.get(option, ((), ()))
    for name in (option, *drop):  # replace the baseline's value
        if name in base:
            i = base.index(name)
            del base[i:i + 2]
    base += add
    bad = spec.templates.get(option, "{}").replace("{}", value)
    before = {p.relative_to(cwd) for p in cwd.rglob("*")}
    old = os.getcwd()
    os.chdir(cwd)
    try:
        result = runner.invoke(app, [spec.command or command, *base, option, bad])
    finally:
        os.chdir(old)
    left = sorted(str(p.relative_to(cwd)) for p in cwd.rglob("*") if p.relative_to(cwd) not in before)
    return result, left


def classify(command: str, option: str, value: str, strict: bool, cwd: Path) -> list[str]:
    """What is wrong with the outcome (empty when it is right): for the fuzz test and the adversarial count."""
    result, left = _invoke(command, option, value, cwd)
    faults = []
    crashed = result.exception is not None and not isinstance(result.exception, SystemExit)
    if crashed or "Traceback" in result.output:
        faults.append(f"traceback: {type(result.exception).__name__}: {str(result.exception)[:200]}")
    if result.exit_code == 2:
        lines = result.stderr.splitlines()
        if len(lines) != 1 or not result.stderr.startswith("error: ") or not result.stderr.endswith("\n"):
            faults.append(f"not one line on stderr: {result.stderr[:300]!r}")
        elif "\x1b" in result.stderr:
            faults.append("escape sequence passed to the terminal")
        if left:
            faults.append(f"files left after the error: {left[:5]}")
    elif result.exit_code == 0:
        if strict:
            faults.append(f"accepted a never-legitimate value (stdout {result.stdout[:200]!r})")
        try:
            json.loads(result.stdout, parse_constant=lambda c: (_ for _ in ()).throw(ValueError(c)))
        except ValueError as exc:
            faults.append(f"silent NaN/inf or no JSON in the output: {str(exc)[:100]}")
    elif not crashed:
        faults.append(f"exit code {result.exit_code}: {result.output[:200]!r}")
    return faults


@pytest.mark.parametrize("command,option,cls,value,strict", _cases())
def test_bad_option_value(tmp_path, command, option, cls, value, strict):
    assert classify(command, option, value, strict, tmp_path) == []


def test_every_command_with_options_is_fuzzed():
    """A new command with value options must get a baseline here (else it would escape the fuzz test)."""
    group = COMMAND
    for name, cmd in group.commands.items():
        values = [p for p in cmd.params if _kind(p) is not None]
        if values:
            assert name in COMMANDS, f"command {name} has value options but no fuzz baseline"


@pytest.mark.parametrize("args", [
    ["uq", "{uq}", "--samples", "1e23"],
    ["uq", "{uq}", "--workers", "0", "--backend", "dask"],
    ["simulate", "--force", "kN", "--alpha0", "0.2", "--f1", "0", "--f2", "0"],
    ["simulate", "--energy", "9**9**9", "--alpha0", "0.2", "--f1", "0", "--f2", "0"],
], ids=["int-parse", "workers", "bare-unit", "power-tower"])
def test_installed_script_one_line(tmp_path, args):
    """Through the real entry point (a subprocess): one line on stderr, exit 2, nothing written."""
    shutil.copy(_data("uq_paper.toml"), tmp_path / "uq.toml")
    args = [a.format(uq="uq.toml") for a in args]
    r = subprocess.run([sys.executable, "-c", "from quickrelease.cli import main; main()", *args], cwd=tmp_path,
                       capture_output=True, text=True, timeout=120,
                       env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert r.returncode == 2, (r.stdout, r.stderr)
    assert r.stderr.startswith("error: ") and r.stderr.count("\n") == 1, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["uq.toml"]


# -- issue 22: output paths and input files of every kind, as an adversary would name them ------------------------

#: Commands that write, with the option naming the output ("{}" for it) and a cheap valid invocation; the
#: output's kind: a folder, or a file with a suffix.
WRITERS = {
    "run --out": (("run", "case.toml", "--out", "{}"), ""),
    "report --out": (("report", "case.toml", "--out", "{}"), ""),
    "demo --out": (("demo", "--out", "{}"), ""),
    "uq --out": (("uq", "uq.toml", "--samples", "400", "--chunk", "200", "--out", "{}"), ""),
    "fit --out": (("fit", "case.toml", "--out", "{}"), ""),
    "plan --out": (("plan", "case.toml", "--out", "{}"), ""),
    "building --out": (("building", "building.toml", "--out", "{}"), ""),
    "sweep --out": (("sweep", "case.toml", "--grid", "F1=100 N:900 N:2", "--out", "{}"), ".nc"),
    "sweep --out zarr": (("sweep", "case.toml", "--grid", "F1=100 N:900 N:2", "--out", "{}"), ".zarr"),
    "synth --out": (("synth", "case.toml", "--channels", "u", "--rate", "200 Hz", "--out", "{}"), ".csv"),
    "synth --case-out": (("synth", "case.toml", "--channels", "u", "--rate", "200 Hz", "--out", "r.csv",
                          "--case-out", "{}"), ".toml"),
}
ROOT = hasattr(os, "geteuid") and os.geteuid() == 0
PATH_CLASSES = ("fifo", "character device", "foreign file", "long name", "long path", "under a file", "empty")


def _path_value(cls: str, suffix: str, rng: random.Random, cwd: Path) -> str:
    """An output path of class ``cls`` (made in ``cwd`` where it must exist), its lengths drawn from ``rng``."""
    name = "target" + suffix
    if cls == "fifo":
        os.mkfifo(cwd / name)
    elif cls == "character device":  # the null device's numbers (1:3), made here: never the machine's own
        os.mknod(cwd / name, 0o666 | 0o020000, os.makedev(1, 3))
    elif cls == "foreign file":
        (cwd / name).write_text("the user's own file\n")
    elif cls == "long name":
        name = "n" * rng.randint(256, 2000) + suffix
    elif cls == "long path":
        depth = rng.randint(21, 60)
        name = "/".join("p" * rng.randint(200, 255) for _ in range(depth)) + "/x" + suffix
    elif cls == "under a file":
        (cwd / "a_file").write_text("x")
        name = "a_file/" + "s" * rng.randint(1, 50) + suffix
    else:
        name = rng.choice(["", " ", "   "])
    return name


def _path_cases():
    rng = random.Random(20261126)
    out = []
    for writer in WRITERS:
        for cls in PATH_CLASSES:  # (a foreign file at a folder command's --out: refused, "is a file")
            marks = [pytest.mark.skipif(not ROOT, reason="mknod needs root")] if cls == "character device" else []
            out.append(pytest.param(writer, cls, rng.randrange(2**32), marks=marks, id=f"{writer}-{cls}"))
    return out


@pytest.mark.parametrize("writer,cls,seed", _path_cases())
def test_an_adversarial_output_path_is_one_line(tmp_path, writer, cls, seed):
    """Every writing command against every kind of output path: refused before any work in one line, exit 2;
    what was at the path is still there as it was (a FIFO, a device node, the user's file), and nothing else
    is left behind."""
    args, suffix = WRITERS[writer]
    shutil.copy(_data("paper.toml"), tmp_path / "case.toml")
    shutil.copy(_data("uq_paper.toml"), tmp_path / "uq.toml")
    (tmp_path / "building.toml").write_text(BUILDING_CASE)
    if writer in ("fit --out", "building --out"):  # cases with a record
        examples = Path(__file__).parents[2] / "examples"
        shutil.copy(examples / ("fit.toml" if writer == "fit --out" else "building.toml"),
                    tmp_path / ("case.toml" if writer == "fit --out" else "building.toml"))
        shutil.copytree(examples / "records", tmp_path / "records")
    value = _path_value(cls, suffix, random.Random(seed), tmp_path)
    before = {p.name: (os.lstat(p).st_mode, p.read_bytes() if p.is_file() else None) for p in tmp_path.iterdir()
              if p.name != "records"}
    old = os.getcwd()
    os.chdir(tmp_path)
    try:
        result = runner.invoke(app, [a.replace("{}", value) for a in args])
    finally:
        os.chdir(old)
    lines = result.stderr.strip().splitlines()
    assert result.exit_code == 2 and len(lines) == 1 and lines[0].startswith("error: "), \
        (result.exit_code, result.stderr[-500:], result.exception)
    assert len(lines[0]) < 500 and "\x1b" not in lines[0]
    after = {p.name: (os.lstat(p).st_mode, p.read_bytes() if p.is_file() else None) for p in tmp_path.iterdir()
             if p.name != "records"}
    assert after == before


INPUT_COMMANDS = {  # a command and its arguments, "{}" the case file
    "simulate": ("simulate", "{}", "--json"), "identify": ("identify", "{}", "--json"),
    "run": ("run", "{}", "--out", "o"), "report": ("report", "{}", "--out", "o"),
    "uq": ("uq", "{}", "--samples", "400"), "sweep": ("sweep", "{}", "--grid", "F1=100 N:900 N:2"),
    "synth": ("synth", "{}"), "fit": ("fit", "{}"), "plan": ("plan", "{}"), "building": ("building", "{}"),
    "campaign": ("campaign", "{}"),
}


@pytest.mark.parametrize("kind", ["fifo", pytest.param("zero", marks=pytest.mark.skipif(not ROOT, reason="root"))])
@pytest.mark.parametrize("command", list(INPUT_COMMANDS))
def test_a_case_file_that_is_not_a_regular_file_is_one_line(tmp_path, command, kind):
    """The case (or campaign) file a FIFO (which would wait for a writer forever) or a device with the zero
    device's numbers (read until memory runs out): one line naming it, "not a regular file", at once (in a
    thread that must end within a minute)."""
    import threading

    path = tmp_path / "special.toml"
    if kind == "fifo":
        os.mkfifo(path)
    else:
        os.mknod(path, 0o666 | 0o020000, os.makedev(1, 5))
    box = []
    args = [a.replace("{}", str(path)) for a in INPUT_COMMANDS[command]]
    thread = threading.Thread(target=lambda: box.append(runner.invoke(app, args)), daemon=True)
    thread.start()
    thread.join(60)
    if thread.is_alive():
        if kind == "fifo":
            with open(path, "w"):
                pass
        pytest.fail("did not return within a minute")
    result = box[0]
    lines = result.stderr.strip().splitlines()
    assert result.exit_code == 2 and len(lines) == 1 and "special.toml: not a regular file" in lines[0], \
        result.stderr


def test_an_epoch_clock_is_a_fuzzed_input(tmp_path):
    """A record on a clock that starts anywhere (seeded: up to 4e9 s, Unix time to 2096) fits to the friction of
    the same record from 0, to a hundredth of a standard error (issue 22, item 7)."""
    import numpy as np

    from quickrelease.io.case import load_case
    from quickrelease.studies.fit import fit_record

    examples = Path(__file__).parents[2] / "examples"
    lines = (examples / "records" / "paper_500Hz.csv").read_text().splitlines()
    lines = lines[:1] + lines[1::5]  # 100 Hz: a quick fit
    shift = random.Random(20261126).uniform(1e8, 4e9)
    results = {}
    for name, offset in (("plain", 0.0), ("epoch", shift)):
        rows = [lines[0]]
        for row in lines[1:]:
            t, rest = row.split(",", 1)
            rows.append(f"{float(t) + offset:.17g},{rest}")
        (tmp_path / f"{name}.csv").write_text("\n".join(rows) + "\n")
        (tmp_path / f"{name}.toml").write_text((examples / "fit.toml").read_text()
                                               .replace("records/paper_500Hz.csv", f"{name}.csv"))
        results[name] = fit_record(load_case(tmp_path / f"{name}.toml"))
    plain, epoch = results["plain"], results["epoch"]
    for f in ("F1", "F2"):
        assert abs(epoch.estimates[f] - plain.estimates[f]) < 0.01 * plain.std_errors[f], (f, shift)
    assert np.isclose(epoch.release_time - shift, plain.release_time, atol=1e-5)
