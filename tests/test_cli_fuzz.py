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
    "demo": Command(("--file", "demo",), {}),
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
