"""The ``quickrelease`` command line (Typer).

Thin: parses quantities at the boundary (pint, via ``units.parse_quantity``), calls
the library, prints a table or one JSON object. Input errors print one line on
stderr and exit with code 2.
"""

from __future__ import annotations

import contextlib
import json
import math
import sys
from collections.abc import Callable, Iterator
from functools import wraps
from pathlib import Path
from typing import Annotated, Any, Literal

import typer
from typer.core import TyperGroup

from .errors import ParameterError, QuickReleaseError

try:  # Typer >= 0.25 carries its own click
    from typer._click.exceptions import ClickException, NoArgsIsHelpError
except ImportError:  # pragma: no cover - Typer on click
    from click.exceptions import ClickException, NoArgsIsHelpError

#: C0 and C1 control characters but newline and tab: what would let user text (a title, a file name, a
#: value) drive the terminal (ANSI colour, OSC title or clipboard sequences) when printed.
_CONTROL = dict.fromkeys([*range(0x00, 0x09), *range(0x0B, 0x20), *range(0x7F, 0xA0)], "?")


def _clean(text: str) -> str:
    """``text`` with every control character but newline and tab shown as '?' (safe to print)."""
    return str(text).translate(_CONTROL)


def _echo(message: Any = "", err: bool = False) -> None:
    """Print a line of a command's output with :func:`_clean` applied: user text (titles, test names, file
    names, notes) reaches the terminal as text, never as escape sequences."""
    typer.echo(_clean(message), err=err)


def _plain_flags(params: list[Any]) -> list[Any]:
    """Flags (--json, --overwrite, --help, ...) shown without a type: ``<bool>`` beside a flag says nothing its
    name does not, and reads as if it took a value."""
    for param in params:
        if getattr(param, "is_flag", False) and param.metavar is None:
            param.metavar = ""
    return params


#: The options that name an output (a folder or a file): an empty value is refused, not taken as '.'.
_PATH_OPTIONS = ("--out", "-o", "--file", "-f", "--case-out")


def _empty_path_option(args: list[str]) -> str | None:
    """The output option given an empty or blank value in ``args`` (``--out ""``, ``--out=``), else None."""
    for i, arg in enumerate(args):
        if arg == "--":
            return None
        name, eq, value = arg.partition("=")
        if name in _PATH_OPTIONS and eq and not value.strip():
            return name
        if arg in _PATH_OPTIONS and i + 1 < len(args) and not args[i + 1].strip():
            return arg
    return None


class _OneLineErrors(TyperGroup):
    """Usage errors (a bad integer, an unknown option, a missing argument) as one line on stderr, exit 2.

    Typer prints a usage box of six or more lines; the command line's rule for bad input is one line."""

    def get_params(self, ctx: Any) -> list[Any]:
        return _plain_flags(super().get_params(ctx))

    def get_command(self, ctx: Any, cmd_name: str) -> Any:
        command = super().get_command(ctx, cmd_name)
        if command is not None:
            _plain_flags(command.get_params(ctx))
        return command

    def main(self, args: Any = None, prog_name: str | None = None, complete_var: str | None = None,
             standalone_mode: bool = True, **extra: Any) -> Any:
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode, **extra)
        empty = _empty_path_option(sys.argv[1:] if args is None else list(args))
        if empty is not None:  # a path option given as "" (the path would be '.', the current folder)
            typer.echo(f"error: {empty} is empty: give a file or folder name", err=True)
            sys.exit(2)
        try:
            code = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except NoArgsIsHelpError as exc:  # the help text, once: Typer's rich help printed it while raising
            if exc.message.strip():  # (a plain help formatter returns it instead)
                typer.echo(exc.message)
            sys.exit(2)
        except ClickException as exc:
            message = " ".join(exc.format_message().split())
            typer.echo(f"error: {_clean(message)}", err=True)
            sys.exit(exc.exit_code)
        except typer.Abort:
            typer.echo("Aborted.", err=True)
            sys.exit(1)
        sys.exit(code if isinstance(code, int) else 0)


app = typer.Typer(
    cls=_OneLineErrors,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    # "markdown", not Typer's default "rich": Rich markup would swallow the case file's table names
    # ([observations], [record], [[tests]]) in every help text.
    rich_markup_mode="markdown",
    context_settings={"help_option_names": ["-h", "--help"]},
    help="Dynamics of the pushing and quick-release device: simulate a release, identify friction.",
)


def _version_callback(value: bool) -> None:
    if value:
        from ._version import __version__

        typer.echo(f"quickrelease {__version__}")
        raise typer.Exit()


@app.callback()
def _main_options(
    version: Annotated[bool, typer.Option("--version", callback=_version_callback, is_eager=True,
                                          help="Print the version and exit.")] = False,
) -> None:
    """Dynamics of the pushing and quick-release device: simulate a release, identify friction."""

DeviceOpt = Annotated[Path | None, typer.Option("--device", help="Device TOML file (Table 2 keys); default: the paper's device.")]
ForceOpt = Annotated[str | None, typer.Option("--force", "-p", help="Push force P at release, e.g. '1598 kN' (SI number: N).")]
EnergyOpt = Annotated[str | None, typer.Option("--energy", help="Stored strain energy E_S, e.g. '2.90 kJ' (SI number: J).")]
Alpha0Opt = Annotated[str | None, typer.Option("--alpha0", help="Angle of the bars with the loading axis at release, e.g. '0.2' or '11.46 deg'.")]
MassOpt = Annotated[str | None, typer.Option("--mass-model", metavar="<distributed|lumped|C>", help="distributed (c = 2/3, default), lumped (c = 1) or a number c.")]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print one JSON object instead of a table.")]
ThreadsOpt = Annotated[int | None, typer.Option("--threads", "-t", help="Threads of the compiled kernels, 1 to the cores numba may use (default: all; results do not depend on it).")]


def _check_threads(threads: int | None, backend: str = "numpy") -> None:
    """--threads: an integer in [1, NUMBA_NUM_THREADS], and not with the Dask backend (checked before any work)."""
    from ._threads import check_threads, refuse_with_dask

    check_threads(threads, "--threads")
    refuse_with_dask(threads, backend, "--threads")


def _fail(message: str) -> None:
    typer.echo(f"error: {_clean(' '.join(str(message).splitlines()))}", err=True)
    raise typer.Exit(code=2)


def _guard(func: Callable[..., Any]) -> Callable[..., Any]:
    """Turn library input errors, and an ``OSError`` no writer turned into one (a full disk, a closed pipe on
    the standard output), into one line on stderr and exit code 2."""

    @wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        import numpy as np

        try:  # floating-point warnings are not for the terminal: results are checked for finiteness instead
            with np.errstate(all="ignore"):
                result = func(*args, **kwargs)
            sys.stdout.flush()  # a full device on the standard output shows here, not at exit
            return result
        except QuickReleaseError as exc:
            _fail(str(exc))
        except RecursionError:
            _fail("an input is nested too deeply to read (a TOML file of thousands of nested arrays or tables?)")
        except OSError as exc:
            _fail(_os_error_line(exc))

    return wrapper


def _os_error_line(exc: OSError) -> str:
    """One line for an OSError that reached the command: a file named when the error names one, else the
    standard output (which is then closed, so that the exit does not try to write to it again)."""
    from .io.runfolder import _reason, _short_path

    if exc.filename is not None:
        return f"{_short_path(exc.filename)}: {_reason(exc)}"
    with contextlib.suppress(OSError, ValueError):  # nothing more reaches the lost standard output
        import os

        fd = os.open(os.devnull, os.O_WRONLY)
        os.dup2(fd, sys.stdout.fileno())
        os.close(fd)
    if isinstance(exc, BrokenPipeError):
        return "the standard output was closed before the output was written (broken pipe)"
    return f"cannot write the standard output: {_reason(exc)}"


def _device(path: Path | None):
    from .device.parameters import load_device, preset

    return preset("paper") if path is None else load_device(path)


def _energy(device, force: str | None, energy: str | None, alpha0: float) -> tuple[float, float | None]:
    """E_S from --energy, or from --force by Eq. 2; returns (E_S, P or None)."""
    from .device.statics import strain_energy
    from .units import parse_quantity

    if (force is None) == (energy is None):
        raise ParameterError("--force/--energy", "both" if force else "neither", "exactly one of the two")
    if energy is not None:
        return parse_quantity(energy, "energy", "--energy"), None
    P = parse_quantity(force, "force", "--force")
    return strain_energy(P, alpha0, device).total, P


def _check_case_optional(case) -> None:
    """The optional packages the case's record files need (``.parquet``: pyarrow, ...), checked before any
    work: one line, exit 2."""
    from .io.records import record_files
    from .studies.distributed import check_optional

    building = getattr(case, "building", None)
    check_optional(files=record_files(case.record) + record_files(getattr(building, "record", None)))


@contextlib.contextmanager
def _busy(what: str) -> Iterator[Callable[[str], None]]:
    """A spinner with ``what`` on stderr while a long computation runs, when stderr is a terminal; it is gone
    before the command prints its results. Yields a function that says what step runs: the spinner's text on a
    terminal, else a throttled ``progress:`` line (:func:`_progress_lines`)."""
    if not sys.stderr.isatty():
        yield _progress_lines(what)
        return
    from rich.console import Console
    from rich.live import Live
    from rich.spinner import Spinner

    spinner = Spinner("dots", text=_clean(what))
    with Live(spinner, console=Console(stderr=True), transient=True, redirect_stdout=False, redirect_stderr=False,
              refresh_per_second=8):
        yield lambda text: spinner.update(text=_clean(f"{what}: {text}"))


#: Seconds a run goes before a pipe or a file is told what runs, and between two such lines at least.
PROGRESS_AFTER, PROGRESS_EVERY = 3.0, 5.0


def _progress_lines(what: str):
    """What a long run is doing, for stderr that is no terminal: a line ``progress: <what>: <step>`` once the run
    has gone ``PROGRESS_AFTER`` seconds, then at most one every ``PROGRESS_EVERY`` seconds (quick runs and
    their errors print nothing more)."""
    import time

    start, last = time.monotonic(), [-math.inf]

    def step(text: str) -> None:
        now = time.monotonic()
        if now - start >= PROGRESS_AFTER and now - last[0] >= PROGRESS_EVERY:
            last[0] = now
            _echo(f"progress: {what}: {text}", err=True)

    return step


def _print_json(data: dict[str, Any]) -> None:
    """One JSON object on stdout; NaN and infinities (a sweep whose every point is out of range) as null, so
    the output is valid JSON."""
    from .io.export import jsonable

    typer.echo(json.dumps(jsonable(data), indent=2, allow_nan=False))


def _table(title: str, rows: list[tuple[str, ...]], headers: tuple[str, ...]) -> None:
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    table = Table(title=escape(_clean(title)), title_justify="left")
    for h in headers:
        table.add_column(escape(_clean(h)))
    for row in rows:
        table.add_row(*(escape(_clean(str(cell))) for cell in row))
    Console().print(table)  # the terminal's width (80 columns when not a terminal)


def _check_output_files(targets, overwrite: bool) -> None:
    """Pre-flight of the files a command writes, ``(path or None, option)`` each: refused (one line) before any
    work when a path names a device node, FIFO or folder, or an existing file without --overwrite, or the
    same file twice (:func:`quickrelease.io.runfolder.check_output_file`)."""
    import os

    from .io.runfolder import OutputError, check_output_file

    seen: dict[str, str] = {}
    for path, option in targets:
        if path is None:
            continue
        full = str(check_output_file(path, option, overwrite))
        key = os.path.realpath(full)
        if key in seen:
            raise OutputError(f"{option} {path}: the same file as {seen[key]}; give two different files")
        seen[key] = option


def _file_option(file: Path, out_old: Path | None, command: str) -> Path:
    """The output file of ``sweep`` and ``synth``: ``--out`` (as every command's output; a file here, where the
    command writes one). Its former name ``--file`` (-f) is still accepted, with a note."""
    if out_old is None:
        return file
    _echo(f"note: {command}: --file is now --out (-o), the output option of every command; --file still works "
          "for now", err=True)
    return out_old


CaseArg = Annotated[Path | None, typer.Argument(help="Case file (TOML); flags override its entries.",
                                                 show_default=False)]


def _case_with_flags(case_file: Path | None, device: Path | None, force: str | None, energy: str | None,
                     alpha0: str | None, mass_model: str | None, **extra: Any):
    """A Case from the file (if any) with the command-line flags applied on top."""
    from ._validate import check_angle
    from .io.case import Case, load_case
    from .units import parse_quantity

    case = load_case(case_file) if case_file is not None else None
    changes: dict[str, Any] = {}
    if device is not None:
        changes["device"] = _device(device)
    dev = changes.get("device", case.device if case else _device(None))
    if alpha0 is not None:
        changes["alpha0"] = parse_quantity(alpha0, "angle", "--alpha0")
        check_angle("alpha0", changes["alpha0"])
    elif case is None:
        raise QuickReleaseError("--alpha0 is missing: give --alpha0 (an angle in (0, pi/2)) or a case file")
    a0 = changes.get("alpha0", case.alpha0 if case else None)
    if force is not None and energy is not None:
        raise ParameterError("--force/--energy", "both", "exactly one of the two")
    if force is not None:
        changes["push_force"] = parse_quantity(force, "force", "--force")
        changes["stored_energy"] = _energy(dev, force, None, a0)[0]
        changes["energy_given"] = False
    elif energy is not None:
        changes["stored_energy"] = parse_quantity(energy, "energy", "--energy")
        changes["energy_given"] = True
        changes["push_force"] = None
    elif case is None:
        raise ParameterError("--force/--energy", "neither", "exactly one of the two")
    if mass_model is not None:
        changes["mass_model"] = mass_model
    changes.update({k: v for k, v in extra.items() if v is not None})
    if case is None:
        changes.pop("device", None)
        changes.pop("alpha0", None)
        return Case(device=dev, alpha0=a0, stored_energy=changes.pop("stored_energy"), **changes)
    return case.replace(**changes)


@app.command()
@_guard
def simulate(
    case_file: CaseArg = None,
    device: DeviceOpt = None,
    force: ForceOpt = None,
    energy: EnergyOpt = None,
    alpha0: Alpha0Opt = None,
    f1: Annotated[str | None, typer.Option("--f1", help="Friction at the central hinges F1, e.g. '420 N' (default 0, noted on stderr).")] = None,
    f2: Annotated[str | None, typer.Option("--f2", help="Friction at the rail supports F2, e.g. '0.8 kN' (default 0, noted on stderr).")] = None,
    mass_model: MassOpt = None,
    method: Annotated[Literal["energy", "rk", "explicit"] | None, typer.Option("--method", help="Solver: the energy first integral (default), Runge-Kutta, or the paper's explicit scheme (Table 6).")] = None,
    dt: Annotated[str | None, typer.Option("--dt", help="Time step of the explicit method, e.g. '1e-4 s'.")] = None,
    out: Annotated[Path | None, typer.Option("--out", "-o", show_default=False, help="Also write the release to this file: .csv or .nc (the time histories, as run's timeseries.csv/.nc) or .json (the --json summary) (default: none, print only).")] = None,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace the file --out names.")] = False,
    as_json: JsonOpt = False,
) -> None:
    """Simulate the release after the fuse breaks; print the stop time, final angle and peaks."""
    from .device.solvers import simulate as run
    from .units import parse_quantity

    F1 = None if f1 is None else parse_quantity(f1, "force", "--f1")
    F2 = None if f2 is None else parse_quantity(f2, "force", "--f2")
    step = None if dt is None else parse_quantity(dt, "time", "--dt")
    _one_file(out, (".csv", ".nc", ".json"), overwrite)
    case = _case_with_flags(case_file, device, force, energy, alpha0, mass_model, F1=F1, F2=F2, method=method,
                            dt=step)
    if case_file is not None and not case.has_friction and case.friction_case is None:
        raise QuickReleaseError("friction is missing: give [friction] in the case file or --f1/--f2 "
                                "(to identify or fit first, use 'quickrelease run')")
    if not case.has_friction and case.friction_case is not None:
        from .studies.fit import case_friction

        F1_case, F2_case, _ = case_friction(case)
        case = case.replace(F1=F1_case, F2=F2_case)
    response = run(case.stored_energy, case.alpha0, case.F1 or 0.0, case.F2 or 0.0, device=case.device,
                   mass_model=case.mass_model, method=case.method, dt=case.dt, n_points=case.n_points,
                   rk_method=case.rk_method, push_force=case.push_force)
    if case_file is None:  # no case file: a friction left out is zero, and the user is told so
        for flag, given, name in (("--f1", f1, "F1"), ("--f2", f2, "F2")):
            if given is None:
                _echo(f"note: {flag} not given: {name} = 0 N (frictionless)", err=True)
    summary = response.summary()
    if out is not None:
        from .io.export import write_csv, write_json, write_netcdf
        from .io.runfolder import provenance

        prov = provenance(case)
        {".csv": lambda: write_csv(response, out), ".nc": lambda: write_netcdf(response, out, provenance=prov),
         ".json": lambda: write_json(summary, out, prov)}[out.suffix.lower()]()
    if as_json:
        _print_json(summary if out is None else {**summary, "files": [str(out)]})
        return
    from .device.response import STOP_REASONS

    words = {"stopped_by": f"{response.stopped_by}: {STOP_REASONS[response.stopped_by]}",
             "stop_time_s": "inf (never arrives)"} if response.stopped_by == "creeps_to_limit" else {}
    from .report.display import label, value_text

    _table("Release", [(label(k), words.get(k, value_text(k, v))) for k, v in summary.items()], ("quantity", "value"))
    if out is not None:
        _echo(f"Wrote 1 file: {out}")


@app.command()
@_guard
def identify(
    case_file: CaseArg = None,
    device: DeviceOpt = None,
    force: ForceOpt = None,
    energy: EnergyOpt = None,
    alpha0: Alpha0Opt = None,
    alpha_final: Annotated[str | None, typer.Option("--alpha-final", help="Observed final angle alpha_F, e.g. '0.7378 rad'.")] = None,
    stop_time: Annotated[str | None, typer.Option("--stop-time", help="Observed time from release to stop t_F, e.g. '1.05 s'.")] = None,
    mass_model: MassOpt = None,
    out: Annotated[Path | None, typer.Option("--out", "-o", show_default=False, help="Also write the identification to this .json file (the --json keys) (default: none, print only).")] = None,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace the file --out names.")] = False,
    as_json: JsonOpt = False,
) -> None:
    """Identify the friction forces F1, F2 from a test (Eq. 11-13, Table 7)."""
    from .device.identify import identify_friction
    from .units import parse_quantity

    _one_file(out, (".json",), overwrite)
    aF = None if alpha_final is None else parse_quantity(alpha_final, "angle", "--alpha-final")
    tF = None if stop_time is None else parse_quantity(stop_time, "time", "--stop-time")
    case = _case_with_flags(case_file, device, force, energy, alpha0, mass_model, alpha_final=aF, stop_time=tF)
    if case.alpha_final is None or case.stop_time is None:
        missing = "--alpha-final" if case.alpha_final is None else "--stop-time"
        raise QuickReleaseError(f"{missing} is missing: give the flag or [observations] in the case file")
    result = identify_friction(case.alpha0, case.alpha_final, case.stop_time, stored_energy=case.stored_energy,
                               device=case.device, mass_model=case.mass_model)
    summary = {**result.summary(), "push_force_N": case.push_force}  # the P that stored E_S, when given
    if out is not None:
        from .io.export import write_json
        from .io.runfolder import provenance

        write_json(summary, out, provenance(case))
    if as_json:
        _print_json(summary if out is None else {**summary, "files": [str(out)]})
        return
    from .report.display import quantity_rows

    _table("Identified friction (Eq. 11-13)", quantity_rows(summary), ("quantity", "value"))
    if out is not None:
        _echo(f"Wrote 1 file: {out}")


OutOpt = Annotated[Path, typer.Option("--out", "-o", help="Output folder (created if needed).")]
OverwriteOpt = Annotated[bool, typer.Option("--overwrite", help="Replace an output holding another run's results.")]


def _written(paths: dict[str, Path], out: Path) -> list[Path]:
    """Every file a folder command wrote into ``out``: its results and the folder's ``manifest.json``."""
    from .io.runfolder import MANIFEST

    files = list(paths.values())
    manifest = Path(out) / MANIFEST
    if manifest.is_file() and manifest not in files:
        files.append(manifest)
    return files


def _listing(paths: dict[str, Path], out: Path) -> None:
    files = _written(paths, out)
    _echo(f"Wrote {len(files)} files to {out}/:")
    for path in files:
        _echo(f"  {path.relative_to(out)}")


def _one_file(out: Path | None, suffixes: tuple[str, ...], overwrite: bool) -> Path | None:
    """Pre-flight of ``--out`` naming one file: a suffix the command writes, a place it can be written, and no
    file already there unless ``--overwrite``."""
    if out is None:
        return None
    from .io.runfolder import check_target

    if out.suffix.lower() not in suffixes:
        raise QuickReleaseError(f"--out {out}: expected a file name ending in {' or '.join(suffixes)}")
    check_target(out, "file")
    if (out.exists() or out.is_symlink()) and not overwrite:
        raise QuickReleaseError(f"--out {out}: a file is already there; give --overwrite to replace it")
    return out


@app.command("run")
@_guard
def run_command(
    case_file: Annotated[Path, typer.Argument(help="Case file (TOML).")],
    out: OutOpt = Path("quickrelease-out"),
    overwrite: OverwriteOpt = False,
    as_json: JsonOpt = False,
) -> None:
    """Do what the case file asks (identify if observed, then simulate) and write all results into --out."""
    from .io.case import load_case
    from .workflow import results_folder, run_case, write_results

    case = load_case(case_file)
    _check_case_optional(case)
    results_folder(case, out, overwrite=overwrite)  # pre-flight: refuse before the work
    result = run_case(case)
    paths = write_results(result, out, overwrite=overwrite)
    _record_notes(result.fit, err=as_json)
    if as_json:
        extra = {} if result.building is None else {"building": result.building.summary()}
        files = {k: str(v) for k, v in paths.items()}
        if (Path(out) / "manifest.json").is_file():
            files.setdefault("manifest", str(Path(out) / "manifest.json"))
        _print_json({"release": result.summary(), "identification": result.identification_summary(), **extra,
                     "files": files})
        return
    from .report.display import label, quantity_rows, value_text

    rows = quantity_rows(result.summary())
    if result.identification is not None:
        i = result.identification
        rows = [(f"{label('F1_N')} (identified)", value_text("F1_N", i.F1)),
                (f"{label('F2_N')} (identified)", value_text("F2_N", i.F2))] + rows
    _table(result.case.title, rows, ("quantity", "value"))
    if result.building is not None:
        _building_tables(result.building, result.building.summary(), f"{result.case.title}: the building")
    if result.plan is not None and result.plan.clearance is not None and result.building is not None:
        c = result.plan.clearance
        _echo(f"Clearance: d0 = {1e3 * c.d0:.4g} mm, {c.describe_minimum()}: "
              f"{'CONTACT' if c.contact else 'no contact'}")
        for text in result.plan.notes:
            if text.startswith("clearance checked with"):
                _echo(f"note: {text}")
    _listing(paths, out)


def _record_notes(fit, err: bool = False) -> None:
    """The notes (rows without a time dropped, samples missing) and warnings of a fit to a record, one line each
    (on stderr with --json, whose stdout is one JSON object)."""
    if fit is None:
        return
    for text in fit.notes:
        _echo(f"note: {text}", err=err)
    for text in fit.warnings:
        _echo(f"warning: {text}", err=err)


@app.command()
@_guard
def report(
    case_file: Annotated[Path, typer.Argument(help="Case file (TOML).")],
    out: OutOpt = Path("quickrelease-out"),
    overwrite: OverwriteOpt = False,
    as_json: JsonOpt = False,
) -> None:
    """Write the self-contained HTML report of a case (figures embedded) as --out/report.html."""
    from .io.case import load_case
    from .workflow import results_folder, run_case, write_results

    case = load_case(case_file)
    _check_case_optional(case)
    results_folder(case, out, figures=False, data=False, overwrite=overwrite)
    paths = write_results(run_case(case), out, figures=False, data=False, overwrite=overwrite)
    files = _written(paths, out)
    if as_json:
        _print_json({"report": str(paths["report"]), "files": [str(p) for p in files]})
        return
    _echo(f"Wrote {len(files)} files to {out}/: {paths['report'].relative_to(out)} (the report), "
          + ", ".join(str(p.relative_to(out)) for p in files if p != paths["report"]))


@app.command()
@_guard
def demo(
    out: OutOpt = Path("quickrelease-demo"),
    overwrite: OverwriteOpt = False,
    as_json: JsonOpt = False,
) -> None:
    """The paper's test: E_S from Eq. 2 at P = 1598 kN, alpha0 = 0.2 rad; Table 7 identified; paper vs us.

    Also writes the figures (Fig. 13-15, identification, strain energy) and the HTML report of the
    paper case into --out. The mass model is the distributed one (c = 2/3): the paper's t_F = 1.05 s is
    infeasible with the lumped one (c = 1), whose feasible interval the comparison reports in a row.
    """
    from dataclasses import replace
    from importlib import resources

    from .device.paper import reproduce_table7
    from .device.parameters import preset
    from .io.case import load_case
    from .workflow import results_folder, run_case, write_results

    mass_model = "distributed"
    with resources.as_file(resources.files("quickrelease") / "data" / "cases" / "paper.toml") as path:
        case = load_case(path).replace(mass_model=mass_model, source="paper case (built in)")
    results_folder(case, out, overwrite=overwrite)  # pre-flight
    dev = preset("paper")
    cmp = reproduce_table7(dev, mass_model=mass_model)
    if as_json:
        paths = write_results(replace(run_case(case), paper=cmp), out, overwrite=overwrite)
        _print_json({"device": dev.name, "mass_model": mass_model, **cmp.summary(), "out": str(out),
                     "files": sorted(str(p) for p in _written(paths, out))})
        return
    _echo(f"Device: {dev.name} (Table 2); mass model: {mass_model}")
    terms = [(k.replace("_", " "), f"{v:.2f}") for k, v in cmp.E_S_breakdown.items()]
    terms.append(("total E_S", f"{cmp.E_S_eq2:.2f}"))
    _table("E_S by term (Eq. 2) [J]", terms, ("term", "J"))
    _table("Table 7: the paper and quickrelease", cmp.rows(), ("quantity", "paper", "quickrelease", "note"))
    _echo(
        f"Release with the identified friction: alpha_dot0 = {cmp.alpha_dot0:.4f} rad/s, "
        f"u_F = {cmp.u_final:.4f} m, v_F = {cmp.v_final:.4f} m, "
        f"peak u_dot = {cmp.peak_u_dot:.3f} m/s, peak v_dot = {cmp.peak_v_dot:.3f} m/s"
    )
    paths = write_results(replace(run_case(case), paper=cmp), out, overwrite=overwrite)
    _echo(f"Figures and report of the paper case: {out / 'report.html'} ({len(_written(paths, out))} files "
          f"in {out}/)")


@app.command()
@_guard
def uq(
    case_file: Annotated[Path, typer.Argument(help="Case file with [observations] and at least one scatter.")],
    samples: Annotated[int, typer.Option("--samples", "-n", help="Monte Carlo samples.")] = 100_000,
    seed: Annotated[int, typer.Option("--seed", help="Seed (results depend on seed and chunk size only).")] = 0,
    chunk: Annotated[int, typer.Option("--chunk", help="Samples per chunk (bounds memory).")] = 1_000_000,
    backend: Annotated[Literal["numpy", "dask", "gpu"], typer.Option("--backend", help="Where the samples are computed: this process, a Dask cluster, or a CUDA GPU (pip install 'quickrelease[gpu]').")] = "numpy",
    scheduler: Annotated[str | None, typer.Option("--scheduler", help="Dask scheduler address; default: a LocalCluster.")] = None,
    workers: Annotated[int, typer.Option("--workers", help="Workers of the LocalCluster.")] = 2,
    out: Annotated[Path | None, typer.Option("--out", "-o", show_default=False, help="Folder for chunks, uq.json and the corner figure (default: none, nothing written).")] = None,
    resume: Annotated[bool, typer.Option("--resume", help="Continue an interrupted run in --out (same inputs only).")] = False,
    threads: Annotated[int | None, typer.Option("--threads", "-t", help="Threads of the compiled kernels, 1 to the cores numba may use (default: all; results do not depend on it); numpy backend only (a Dask task runs on one thread; the gpu backend needs none).")] = None,
    overwrite: OverwriteOpt = False,
    as_json: JsonOpt = False,
) -> None:
    """Uncertainty of the identified F1, F2 from the scatter of the observations (Monte Carlo)."""
    from .io.case import load_case
    from .studies.uq import run_uq

    _check_threads(threads, backend)
    case = load_case(case_file)
    result = run_uq(case, samples, seed=seed, chunk=chunk, backend=backend, scheduler=scheduler, workers=workers,
                    out=out, resume=resume, overwrite=overwrite, progress=not as_json and sys.stderr.isatty(),
                    log=lambda line: _echo(f"note: {line}", err=True), threads=threads)
    if as_json:
        _print_json(result.summary())
        return
    from .report.display import key_for, number, quantity

    rows = [(key_for(k)[0], v) for k, v in result.inputs.items()]
    _table("Uncertain inputs", rows, ("input", "distribution"))
    p = result.percentiles
    _table(f"Identified friction over {result.samples:,} samples (seed {result.seed})", [
        (key_for(name)[0], *(quantity(v, "N") for v in (result.nominal[name], p[name]["p2.5"], p[name]["p50"],
                                                         p[name]["p97.5"], result.std[name])))
         for name in ("F1", "F2")], ("friction", "nominal", "2.5%", "50%", "97.5%", "std"))
    _echo(f"correlation(F1, F2) = {result.correlation:.4f}; infeasible samples: "
          f"{100 * result.infeasible_share:.2f}%; percentile resolution {quantity(result.resolution['F1'], 'N', 3)}")
    sens = [(f"d{f}/d{x}", f"N/{key_for(x)[1]}" if key_for(x)[1] else "N", number(v),
             number(result.sensitivities_fd[f][x])) for f in ("F1", "F2") for x, v in result.sensitivities[f].items()]
    _table("Local sensitivities at the nominal point", sens, ("derivative", "unit", "implicit function",
                                                                "finite diff."))


def _grids(texts: list[str], parse_grid) -> dict[str, Any]:
    """The --grid options as {name: values}; a name given twice is refused (one would be lost)."""
    grids: dict[str, Any] = {}
    for text in texts:
        name, values = parse_grid(text)
        if name in grids:
            raise QuickReleaseError(f"--grid {text}: {name} is given twice (one --grid per input)")
        grids[name] = values
    return grids


@app.command("sweep")
@_guard
def sweep_command(
    case_file: Annotated[Path, typer.Argument(help="Case file: the inputs not swept, and the device.")],
    grid: Annotated[list[str], typer.Option("--grid", "-g", help="NAME=start:stop:count (with units), e.g. 'force=500 kN:3000 kN:26'; repeat for more dimensions.")],
    file: Annotated[Path, typer.Option("--out", "-o", help="Output file: .nc (NetCDF) or .zarr (Zarr store); the heat maps beside it.")] = Path("sweep.nc"),
    out_old: Annotated[Path | None, typer.Option("--file", "-f", hidden=True, help="Former name of --out.")] = None,
    backend: Annotated[Literal["numpy", "dask", "gpu"], typer.Option("--backend", help="Where the grid is computed: this process, a Dask cluster (needs --out *.zarr), or a CUDA GPU (pip install 'quickrelease[gpu]').")] = "numpy",
    scheduler: Annotated[str | None, typer.Option("--scheduler", help="Dask scheduler address; default: a LocalCluster.")] = None,
    workers: Annotated[int, typer.Option("--workers", help="Workers of the LocalCluster.")] = 2,
    resume: Annotated[bool, typer.Option("--resume", help="Continue an interrupted dask sweep in --out (same inputs only).")] = False,
    block_rows: Annotated[int | None, typer.Option("--block-rows", help="Rows of the first grid per Dask block (default: about 10^6 points a block).")] = None,
    threads: Annotated[int | None, typer.Option("--threads", "-t", help="Threads of the compiled kernels, 1 to the cores numba may use (default: all; results do not depend on it); numpy backend only (a Dask task runs on one thread; the gpu backend needs none).")] = None,
    overwrite: OverwriteOpt = False,
    as_json: JsonOpt = False,
) -> None:
    """Release envelope (t_F, alpha_F, u_F, v_F, peak velocities) over a grid of inputs."""
    from .io.case import load_case
    from .io.runfolder import provenance
    from .report.plots import save_figure
    from .studies.sweep import heatmap_figure, parse_grid, sweep

    _check_threads(threads, backend)
    out = _file_option(file, out_old, "sweep")
    grids = _grids(grid, parse_grid)
    stem = out.name.rsplit(".", 1)[0] + "_heatmaps"
    if out.suffix in (".nc", ".zarr"):  # the figures beside it: companions of the file, checked alike
        from .io.runfolder import check_target

        check_target(out, "file" if out.suffix == ".nc" else "folder", "--out")
        _check_output_files(((out.parent / f"{stem}.{fmt}", "--out") for fmt in ("png", "svg")),
                            overwrite or out.exists())
    case = load_case(case_file)
    with _busy("sweeping the grid"):
        ds = sweep(case, grids, backend=backend, out=out, scheduler=scheduler, workers=workers,
                   block_rows=block_rows, resume=resume, overwrite=overwrite,
                   log=lambda line: _echo(f"note: {line}", err=True), threads=threads)
        figs = save_figure(heatmap_figure(ds), out.parent, stem)
    summary = {"file": str(out), "dims": {k: int(v) for k, v in ds.sizes.items()},
               "stop_time_s": [float(ds.stop_time.min()),  # creeping cases (stopped_by 2, t_F = inf): counted apart
                               float(ds.stop_time.where(ds.stopped_by != 2).max())],
               "creeps_to_limit_count": int((ds.stopped_by == 2).sum()),
               "u_final_m": [float(ds.u_final.min()), float(ds.u_final.max())],
               "v_final_m": [float(ds.v_final.min()), float(ds.v_final.max())],
               "peak_v_dot_m_s": [float(ds.peak_v_dot.min()), float(ds.peak_v_dot.max())],
               "geometric_limit_share": float((ds.stopped_by == 1).mean()),
               "flagged": int((ds.status != 0).sum()),  # outputs NaN, the reason in the status variable
               "figures": [str(p) for p in figs.values()], "provenance": provenance(case)}
    if as_json:
        _print_json(summary)
        return
    from .report.display import quantity_rows

    rows = quantity_rows(summary, skip=("dims", "provenance", "figures"))
    rows.append(("figures", ", ".join(summary["figures"])))
    _table(f"Sweep over {' x '.join(f'{k} ({v})' for k, v in summary['dims'].items())}", rows,
           ("quantity", "value (min, max)"))


@app.command()
@_guard
def synth(
    case_file: Annotated[Path, typer.Argument(help="Case file: device, test set-up, and [friction] or [observations]; or [building] (with --building, or a case of the building alone).")],
    channels: Annotated[str | None, typer.Option("--channels", "-c", help="Comma list of alpha, alpha_dot, u, v, u_dot, v_dot, a_head, a_hinge (default u,v,a_head); building: x, v, a, x_roof, v_roof, a_roof (default x,a).")] = None,
    rate: Annotated[str | None, typer.Option("--rate", help="Sampling rate, e.g. '500 Hz' (default 500 Hz; building 200 Hz).")] = None,
    noise: Annotated[list[str] | None, typer.Option("--noise", help="Noise std per channel, e.g. 'u=0.5 mm,a_head=0.05 m/s^2' (repeatable); defaults: alpha 0.002 rad, u and v 0.5 mm, velocities 5 mm/s, accelerations 0.05 m/s^2; building: x 0.05 mm, v 1 mm/s, a 0.002 g0.")] = None,
    offset: Annotated[list[str] | None, typer.Option("--offset", help="Constant offset per channel, e.g. 'u=2 mm,v=-3 mm' (repeatable).")] = None,
    release_time: Annotated[str | None, typer.Option("--release-time", help="Release instant from the start of the record (default 0.5 s; building 2 s).")] = None,
    duration: Annotated[str | None, typer.Option("--duration", help="Record length (default: release + t_F + max(0.5 s, t_F/4); building: release + min(stop, 20 T) + 2 T).")] = None,
    seed: Annotated[int, typer.Option("--seed", help="Seed of the noise.")] = 0,
    jitter: Annotated[float, typer.Option("--jitter", help="Uneven sampling: instants shifted by up to +-jitter/2 intervals, in [0, 1).")] = 0.0,
    missing: Annotated[float, typer.Option("--missing", help="Share of missing samples per channel, in [0, 1).")] = 0.0,
    building: Annotated[bool, typer.Option("--building", help="Synthesize the building's free vibration ([building]) instead of the device's release (implied by a case without [test]).")] = False,
    file: Annotated[Path, typer.Option("--out", "-o", help="Record file to write (CSV).")] = Path("record.csv"),
    out_old: Annotated[Path | None, typer.Option("--file", "-f", hidden=True, help="Former name of --out.")] = None,
    case_out: Annotated[Path | None, typer.Option("--case-out", help="Also write a case file that fits this record.")] = None,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace an existing --out or --case-out (a device node, FIFO or folder never).")] = False,
    as_json: JsonOpt = False,
) -> None:
    """A synthetic record of the case's release (offsets, noise), and the precision a fit to it would have;
    or (--building) of the building's free vibration after the release, and the precision of its isolation fit."""
    import os

    out = _file_option(file, out_old, "synth")
    from .io.case import load_case
    from .io.export import write_text
    from .studies.synth import case_toml, parse_channel_values, predicted_errors, synthesize
    from .units import parse_quantity

    _check_output_files(((out, "--out"), (case_out, "--case-out")), overwrite)
    case = load_case(case_file, require_test=False)
    if building or not case.has_test:
        _synth_building(case, channels, rate, noise, offset, release_time, duration, seed, jitter, missing, out,
                        case_out, as_json)
        return
    names = [c.strip() for c in ("u,v,a_head" if channels is None else channels).split(",") if c.strip()]
    syn = synthesize(case, names, rate=parse_quantity("500 Hz" if rate is None else rate, "frequency", "--rate"),
                     noise=parse_channel_values(noise or [], "--noise"),
                     offsets=parse_channel_values(offset or [], "--offset"),
                     release_time=parse_quantity("0.5 s" if release_time is None else release_time, "time", "--release-time"),
                     duration=None if duration is None else parse_quantity(duration, "time", "--duration"),
                     seed=seed, jitter=jitter, missing=missing)
    pred = predicted_errors(case, syn)  # everything that can fail comes before the first file is written
    rel_file = out.name if case_out is None else os.path.relpath(out.resolve(), case_out.resolve().parent)
    table = syn.record_table(rel_file)
    case_text = None if case_out is None else case_toml(case, table, f"Fit to {out.name}")
    syn.write_csv(out)
    if case_out is not None:
        write_text(case_text, case_out)
    summary = {"file": str(out), "rows": int(syn.t.size), "rate_Hz": syn.rate, "channels": names,
               "truth": syn.truth, "noise": syn.noise, "offsets": syn.offsets, "seed": seed,
               "predicted": pred, "case_file": None if case_out is None else str(case_out)}
    if as_json:
        _print_json(summary)
        return
    from .report.display import key_for, quantity

    t = syn.truth
    _echo(f"Wrote {out} ({syn.t.size} rows at {syn.rate:g} Hz, channels {', '.join(names)}); friction "
          f"{syn.notes[0].removeprefix('friction ')}: F1 = {quantity(t['F1'], 'N')}, F2 = {quantity(t['F2'], 'N')}; "
          f"release at {quantity(t['release_time'], 's')}, stop {quantity(t['stop_time'], 's')} later at alpha_F = "
          f"{quantity(t['alpha_final'], 'rad')}")
    def se_row(f: str) -> tuple[str, str, str]:  # None: a standard error this record cannot give (SE inf)
        se, rel = pred[f"{f}_se_N"], pred[f"{f}_rel_se"]
        return (key_for(f)[0], "not identified" if se is None else quantity(se, "N", 2),
                "-" if rel is None else f"{100 * rel:.2g}%")

    corr = pred["correlation_F1_F2"]
    _table("Precision of a fit to such a record (Cramer-Rao bound at the truth)", [
        se_row("F1"), se_row("F2"), ("correlation(F1, F2)", "-" if corr is None else f"{corr:+.4f}", ""),
    ], ("", "standard error", "relative"))
    if case_out is not None:
        _echo(f"Wrote {case_out}: quickrelease fit {case_out}")
    else:
        _echo("To fit it, add to a case file:\n" + table)


def _synth_building(case, channels: str | None, rate: str | None, noise: list[str] | None, offset: list[str] | None,
                    release_time: str | None, duration: str | None, seed: int, jitter: float, missing: float,
                    out: Path, case_out: Path | None, as_json: bool) -> None:
    """``synth`` of the building: a record of its free vibration from ``[building]`` (the truth)."""
    import math
    import os

    from .io.building_case import BUILDING_CHANNELS
    from .io.export import write_text
    from .studies.synth import (
        building_case_toml,
        describe_truth,
        parse_channel_values,
        predicted_building_errors,
        synthesize_building,
    )
    from .units import parse_quantity

    if case.building is None:
        raise QuickReleaseError(f"{case.source}: --building needs a [building] table (the building to simulate)")
    names = [c.strip() for c in ("x,a" if channels is None else channels).split(",") if c.strip()]
    syn = synthesize_building(case, names, rate=parse_quantity("200 Hz" if rate is None else rate, "frequency", "--rate"),
                              noise=parse_channel_values(noise or [], "--noise", BUILDING_CHANNELS),
                              offsets=parse_channel_values(offset or [], "--offset", BUILDING_CHANNELS),
                              release_time=parse_quantity("2 s" if release_time is None else release_time, "time", "--release-time"),
                              duration=None if duration is None else parse_quantity(duration, "time", "--duration"),
                              seed=seed, jitter=jitter, missing=missing)
    # everything that can fail comes before the first file is written
    pred = predicted_building_errors(syn)
    rel_file = out.name if case_out is None else os.path.relpath(out.resolve(), case_out.resolve().parent)
    table = syn.record_table(rel_file)
    case_text = None if case_out is None else building_case_toml(case, syn, table, f"The building's record {out.name}")
    syn.write_csv(out)
    if case_out is not None:
        write_text(case_text, case_out)
    summary = {"file": str(out), "rows": int(syn.t.size), "rate_Hz": syn.rate, "channels": names,
               "truth": syn.truth, "noise": syn.noise, "offsets": syn.offsets, "seed": seed, "notes": syn.notes,
               "predicted": pred.summary(), "case_file": None if case_out is None else str(case_out)}
    if as_json:
        _print_json(summary)
        return
    from .report.display import key_for, quantity, split_key

    t = syn.truth
    stop = "still moving at the end" if t["stop_time_s"] is None else f"sticks {quantity(t['stop_time_s'], 's')} later"
    sup = "" if t["model"] != "2dof" else (f" (superstructure {quantity(t['superstructure_mass_kg'], 'kg')}, T_s = "
                                           f"{quantity(t['superstructure_period_s'], 's')}, zeta_s = "
                                           f"{quantity(t['superstructure_damping_ratio'])})")
    _echo(f"Wrote {out} ({syn.t.size} rows at {syn.rate:g} Hz, channels {', '.join(names)}); {t['model']} isolation, "
          f"{describe_truth(t)}{sup}; released from d0 = {quantity(1e3 * t['d0_m'])} mm at "
          f"{quantity(t['release_time_s'], 's')}, {stop}")
    for note in syn.notes:
        _echo(f"note: {note}")
    _table(f"Precision of a {t['model']} fit to it (Cramer-Rao bound)",
           [(key_for(split_key(key)[0], row["unit"])[0], quantity(row["truth"], row["unit"]),
             quantity(row["se"], row["unit"], 2) if math.isfinite(row["se"]) else "not determined",
             "" if row["relative_se"] is None or not math.isfinite(row["se"]) else f"{100 * row['relative_se']:.2g}%")
            for key, row in pred.physical().items()], ("parameter", "truth", "standard error", "relative"))
    for warning in pred.warnings:
        _echo(f"warning: {warning}")
    if case_out is not None:
        _echo(f"Wrote {case_out}: quickrelease building {case_out}")
    else:
        _echo("To read it, add to a case file's [building]:\n" + table)


@app.command("fit")
@_guard
def fit_command(
    case_file: Annotated[Path, typer.Argument(help="Case file with [record] (and/or [observations] with a scatter).")],
    out: Annotated[Path | None, typer.Option("--out", "-o", show_default=False, help="Also write fit.json, figures and report.html into this folder (default: none, print only).")] = None,
    overwrite: OverwriteOpt = False,
    as_json: JsonOpt = False,
) -> None:
    """Fit F1 and F2 (with 95% intervals) to a measured record by weighted least squares."""
    from .io.case import load_case
    from .studies.fit import fit_record

    case = load_case(case_file)
    _check_case_optional(case)
    if case.record is not None:
        from .workflow import results_folder, run_case, write_results

        if out is not None:
            results_folder(case, out, overwrite=overwrite)  # pre-flight
        with _busy("fitting the record"):
            result = run_case(case)
            fit = result.fit
            paths = write_results(result, out, overwrite=overwrite) if out is not None else {}
    else:
        from .io.runfolder import RunFolder, case_inputs

        folder = RunFolder(out, "fit", {"case": case_inputs(case)}, overwrite=overwrite) if out is not None else None
        with _busy("fitting the record"):
            fit = fit_record(case)
        paths = {}
        if folder is not None:
            from .io.export import write_json
            from .io.runfolder import provenance

            with folder.staged() as work:
                paths = {"fit": folder.final(write_json(fit.summary(), work / "fit.json", provenance(case)))}
    summary = fit.summary()
    if as_json:
        _print_json(summary)
        return
    from .io.records import CHANNELS
    from .report.display import estimate_row, quantity

    units = {f"offset_{n}": unit for n, (_, unit, _) in CHANNELS.items()}
    rows = [estimate_row(name, fit.estimates[name], fit.std_errors[name], fit.ci95[name], units.get(name))
            for name in fit.names]
    chi2 = "n/a (no degrees of freedom)" if fit.chi2_reduced is None else f"{fit.chi2_reduced:.4g}"
    title = f"Fit of {case.title}: {'converged' if fit.converged else 'NOT converged'}, " \
            f"reduced chi-square {chi2}, start values from {fit.start_source}"
    _table(title, rows, ("parameter", "estimate", "std. error", "95% interval"))
    if fit.residual_rms:
        unit = {n: CHANNELS[n][1] if n in CHANNELS else "" for n in fit.residual_rms}
        _table("Channels", [(n, str(fit.samples[n]), quantity(fit.noise[n], unit[n], 3), fit.noise_source[n],
                             quantity(fit.residual_rms[n], unit[n], 3)) for n in fit.residual_rms],
               ("channel", "samples", "noise std", "from", "rms residual"))
    i1, i2 = fit.names.index("F1"), fit.names.index("F2")
    _echo(f"correlation(F1, F2) = {fit.correlation[i1, i2]:+.4f}; model stop t_F = {quantity(fit.stop_time, 's')} "
          f"at alpha_F = {quantity(fit.alpha_final, 'rad')}")
    for text in (*fit.notes, *fit.warnings):
        _echo(f"note: {text}" if text in fit.notes else f"warning: {text}")
    if paths:
        _listing(paths, out)


@app.command("building")
@_guard
def building_command(
    case_file: Annotated[Path, typer.Argument(help="Case file with [building] and [building.record].")],
    model: Annotated[Literal["linear", "bilinear", "2dof", "pendulum", "boucwen"] | None, typer.Option("--model", help="Isolation model (default: the case's [building] model): linear or bilinear rubber with sliders, 2dof (a flexible superstructure), pendulum (curved surface sliders, Constantinou's mu(v)), boucwen (lead-rubber, high-damping rubber).")] = None,
    damping: Annotated[Literal["viscous", "power"] | None, typer.Option("--damping", help="The damper's law (default: the case's [building] damping): viscous, or power (a fluid viscous damper, C |v|^alpha).")] = None,
    compare: Annotated[bool, typer.Option("--compare", help="Also fit the other models; rank them by AIC/BIC and residual whiteness.")] = False,
    flexible: Annotated[bool | None, typer.Option("--flexible/--rigid", show_default=False, help="The bilinear, pendulum or boucwen layer under a flexible superstructure ([building] superstructure_mass at the roof; its period and damping fitted), or under a rigid one (default: the case's [building] flexible, else rigid). The linear layer's flexible model is --model 2dof.")] = None,
    out: Annotated[Path | None, typer.Option("--out", "-o", show_default=False, help="Also write summary.json, the record, model and residuals (timeseries.csv, .nc), the figures and report.html into this folder (default: none, print only).")] = None,
    overwrite: OverwriteOpt = False,
    as_json: JsonOpt = False,
) -> None:
    """Identify the building's isolation system (period or k1/k2/F_y, damping, friction) from its free vibration."""
    from .io.building_case import load_building
    from .io.case import load_case
    from .studies.building_analysis import MODELS, analyse_building

    if model is not None and model not in MODELS:
        raise ParameterError("--model", model, ", ".join(MODELS))
    case = load_case(case_file, require_test=False)
    _check_case_optional(case)
    data = load_building(case)
    if not data.channels:
        raise QuickReleaseError(f"{case_file}: no [building.record]: the building command needs the building's "
                                "free-vibration record")
    if out is not None:
        from .workflow import building_folder

        building_folder(data, out, model=model, compare=compare, overwrite=overwrite)  # pre-flight
    with _busy(f"fitting the {model or data.model} isolation model") as step:
        result = analyse_building(data, model=model, compare=compare, progress=step, damping=damping,
                                  flexible=flexible)
    paths = {}
    if out is not None:
        from .workflow import write_building_results

        paths = write_building_results(result, data, out, model=model, compare=compare, title=case.title,
                                       overwrite=overwrite, origin=case)
    summary = result.summary()
    if as_json:
        _print_json(summary)
        return
    _building_tables(result, summary, case.title)
    if paths:
        _listing(paths, out)


def _building_tables(result, summary: dict[str, Any], title: str) -> None:
    """The building's estimates, channels, comparison and decay cross-check as tables; notes and warnings."""
    from .building.model import RECORD_CHANNELS
    from .report.display import estimate_row, key_for, number, quantity, split_key

    fit = result.fit
    rows = []
    for key in ("period_s", "radius_m", "k1_N_m", "k2_N_m", "Fy_N", "Kd_N_m", "Qd_N", "dy_m", "shape",
                "friction_slow", "friction_fast", "rate_s_m", "friction_coefficient", "damping_ratio",
                "damping_coefficient",
                "damping_exponent", "friction_N", "superstructure_period_s", "superstructure_damping_ratio"):
        if summary.get(key) is not None:
            name, unit, _ = split_key(key)
            human, value, _, interval = estimate_row(name, summary[key], None, summary.get(f"{key}_ci95"), unit)
            rows.append((human, value, "not identified" if key in summary.get("not_identified", ()) else interval))
    state = "converged" if fit.converged else "NOT converged"
    cert = fit.search
    if cert is not None:
        found = (f"global minimum {'confirmed' if cert.global_minimum_confirmed else 'NOT confirmed'} "
                 f"({cert.reached_best} of {cert.starts} starts reached it; next minimum "
                 + (f"delta chi-square {number(cert.next_best_delta_chi2, 2)})"
                    if math.isfinite(cert.next_best_delta_chi2) else "none found)"))
        state = f"{state}, {found}"
    _table(f"{title}: {fit.label} isolation model, {state}, reduced chi-square {fit.chi2_reduced:.4g}, "
           f"AIC {fit.aic:.6g}, BIC {fit.bic:.6g}", rows, ("parameter", "estimate", "95% interval"))
    unit = {c.name: RECORD_CHANNELS[c.name][1] if c.name in RECORD_CHANNELS else "" for c in fit.channels}
    _table("Channels", [(c.name, c.kind, str(fit.samples[c.name]), quantity(fit.noise[c.name], unit[c.name], 3),
                         fit.noise_source[c.name], quantity(fit.residual_rms[c.name], unit[c.name], 3),
                         number(fit.whiteness_p[c.name], 3)) for c in fit.channels],
           ("channel", "kind", "samples", "noise std", "from", "rms residual", "whiteness p"))
    if result.comparison:
        _table("Model comparison (lowest BIC first)", [
            (r["model"], str(r["parameters"]), f"{r['aic']:.6g}", f"{r['delta_aic']:.4g}", f"{r['bic']:.6g}",
             f"{r['delta_bic']:.4g}") for r in result.comparison],
            ("model", "parameters", "AIC", "dAIC", "BIC", "dBIC"))
    rows = result.decay_check.get("rows", [])
    if rows:
        _table("Decay cross-check (model-free, combined decrement law)", [
            (key_for(r["parameter"])[0], *estimate_row(r["parameter"], r["fit"], r["decay_se"])[1:2],
             *estimate_row(r["parameter"], r["decay"], r["decay_se"])[1:3], f"{r['difference_in_se']:+.3g}")
            for r in rows],
            ("parameter", "fit", "decay", "decay SE", "difference [SE]"))
    judged = summary.get("effective_judgement")
    if judged and judged.get("cycles"):
        from .report.display import (
            CYCLE_HEADERS,
            DEVIATION_HEADERS,
            SPREAD_HEADERS,
            effective_deviation_rows,
            effective_quantity_rows,
            spread_rows,
        )

        _table("Engineering quantities per cycle (the fitted model's loop)",
               effective_quantity_rows(judged, summary["effective"]), CYCLE_HEADERS)
        _table("The cycles against the identified model's curve at their amplitudes (difference and the 95% band's "
               "half-width, % of the model)", effective_deviation_rows(judged), DEVIATION_HEADERS)
        _table("Spread of the cycles about the model's curve (keff within "
               f"{judged['keff_tolerance']:.0%}, EDC at least {judged['edc_fraction']:.0%}; the cycle from the release "
               "not judged)", spread_rows(judged), SPREAD_HEADERS)
    for text in result.notes:
        _echo(f"note: {text}")
    for text in result.warnings:
        _echo(f"warning: {text}")


@app.command()
@_guard
def campaign(
    campaign_file: Annotated[Path, typer.Argument(help="Campaign file (TOML): shared device and record mapping, [[tests]].")],
    out: Annotated[Path | None, typer.Option("--out", "-o", show_default=False, help="Also write campaign.json, the figure and report.html into this folder (default: none, print only).")] = None,
    overwrite: OverwriteOpt = False,
    as_json: JsonOpt = False,
) -> None:
    """Friction of every test of a campaign, and its laws in the load and the angle (F = a + b x); or, for a
    campaign file with [building], the isolation system of every release and its laws in the amplitude."""
    from .studies.campaign import VARIABLES, run_campaign
    from .workflow import campaign_folder, write_campaign_results

    if out is not None:
        campaign_folder(campaign_file, out, overwrite=overwrite)  # pre-flight
    with _busy("fitting every test of the campaign"):
        result = run_campaign(campaign_file)
        paths = {}
        if out is not None:
            paths = write_campaign_results(result, out, overwrite=overwrite)
    if as_json:
        _print_json(result.summary())
        return
    if getattr(result, "kind", "device") == "building":
        _building_campaign_tables(result)
        if paths:
            _listing(paths, out)
        return

    from .report.display import number, plus_minus, quantity

    _table(f"{result.title}: friction per test", [
        (t.name, quantity(t.case.push_force, "N"), quantity(t.case.alpha0, "rad"), plus_minus(t.F1, t.F1_se, "N"),
         plus_minus(t.F2, t.F2_se, "N"), t.method) for t in result.tests],
        ("test", "push force P", "release angle alpha0", "F1", "F2", "from"))
    rows = []
    for law in result.laws.values():
        _, _, _, scale, unit = VARIABLES[law.variable]
        rows.append((f"{law.friction} = a + b {law.variable}", plus_minus(law.intercept, law.intercept_se, "N"),
                     plus_minus(law.slope / scale, law.slope_se / scale, f"N/{unit}"), number(law.p_value, 2),
                     "yes" if law.significant else "no"))
    _table("Friction laws (weighted least squares; p of slope = 0)", rows,
           ("law", "a", "b", "p", "significant at 5%"))
    for friction, joint in result.joint.items():
        terms = joint.summary()["terms"]
        units = {n: VARIABLES[n][3:] if n in VARIABLES else (1.0, "") for n in terms}
        _echo(f"joint law {friction} = a + " + " + ".join(f"b_{v} {v}" for v in joint.variables) + ": " + ", ".join(
            f"{'a' if n == 'intercept' else 'b_' + n} = "
            f"{plus_minus(v['value'] / units[n][0], v['se'] / units[n][0], 'N' + ('/' + units[n][1] if units[n][1] else ''))}"
            f" (p = {number(v['p_value'], 2)})" for n, v in terms.items()))
    if paths:
        _listing(paths, out)


def _building_campaign_tables(result) -> None:
    """The tables of a building campaign: each release's estimates, then the laws in the amplitude."""
    from .report.display import number, plus_minus
    from .studies.building_campaign import BUILDING_VARIABLES, QUANTITIES

    qs = result.columns  # the quantities with laws, then those reported per release (2dof: T_s, zeta_s)
    rows = []
    for r in result.releases:
        cells = [r.name, number(abs(r.d0) * 1e2, 4), "-" if r.force is None else number(r.force / 1e3, 4)]
        for q in qs:
            scale = QUANTITIES[q][2]
            cells.append(plus_minus(r.values[q] * scale, r.std_errors[q] * scale))
        rows.append(tuple(cells))
    _table(f"{result.title}: the {result.model} isolation system per release (± standard error)", rows,
           ("release", "|d0| [cm]", "P [kN]", *(f"{QUANTITIES[q][4]} [{QUANTITIES[q][3]}]" for q in qs)))
    rows = []
    for law in result.laws.values():
        _, _, y_scale, y_unit, symbol = QUANTITIES[law.quantity]
        _, _, x_scale, x_unit = BUILDING_VARIABLES[law.variable]
        factor = y_scale / x_scale
        rows.append((f"{symbol} = a + b {law.variable}", plus_minus(law.intercept * y_scale, law.intercept_se * y_scale,
                                                                    y_unit),
                     plus_minus(law.slope * factor, law.slope_se * factor,
                                y_unit + (f"/{x_unit}" if x_unit != "-" else "")),
                     number(law.p_value, 2), "yes" if law.significant else "no"))
    _table("Laws in the amplitude (weighted least squares; p of slope = 0)", rows,
           ("law", "a", "b", "p", "significant at 5%"))
    laws = getattr(result, "cycle_laws", {})
    if laws:
        from .studies.building_campaign import CYCLE_QUANTITIES

        rows = []
        for law in laws.values():
            _, _, y_scale, y_unit, symbol = CYCLE_QUANTITIES[law.quantity]
            x = "D [m]" if law.variable == "displacement" else "ln(D / 1 m)"
            per = "/m" if law.variable == "displacement" else ""
            rows.append((f"{symbol} = a + b {x}", plus_minus(law.intercept * y_scale, law.intercept_se * y_scale,
                                                             y_unit),
                         plus_minus(law.slope * y_scale, law.slope_se * y_scale, y_unit + per),
                         number(law.p_value, 2), "yes" if law.significant else "no"))
        _table(f"Laws of the cycles' keff and beta_eff in the cycle amplitude D ({len(result.cycles)} cycles of the "
               "releases' fitted models pooled; unweighted)", rows, ("law", "a", "b", "p", "significant at 5%"))
    for q, names in getattr(result, "left_out", {}).items():
        no_law = "" if any(k[0] == q for k in result.laws) else "; fewer than three releases identify it: no law"
        _echo(f"note: {QUANTITIES[q][4]}: release(s) {', '.join(names)} left out of its laws (their records do not "
              f"identify it){no_law}")
    for r in result.releases:
        if r.restarted_from:
            _echo(f"note: release {r.name} was refitted from the estimates of {r.restarted_from} (its first fit "
                  "misfit its record)")
        for text in r.fit.warnings:
            _echo(f"warning: release {r.name}: {text}")


@app.command()
@_guard
def plan(
    case_file: Annotated[Path, typer.Argument(help="Case file: the planned push ([test] force, alpha0), the friction estimate, and optionally [fuse], [building], [plan].")],
    out: Annotated[Path | None, typer.Option("--out", "-o", show_default=False, help="Also write plan.json, the figures and report.html into this folder (default: none, print only).")] = None,
    threads: ThreadsOpt = None,
    overwrite: OverwriteOpt = False,
    as_json: JsonOpt = False,
) -> None:
    """Plan a test: fuse and angle, member checks, release envelope, clearance with the building."""
    from .io.case import load_case
    from .workflow import results_folder, run_case, write_results

    _check_threads(threads)
    case = load_case(case_file)
    if out is not None:
        results_folder(case, out, plan=True, overwrite=overwrite)  # pre-flight
    with _busy("planning the test"):
        result = run_case(case, plan=True, threads=threads)
    plan_result = result.plan
    paths = write_results(result, out, overwrite=overwrite) if out is not None else {}
    summary = plan_result.summary()
    if as_json:
        _print_json(summary)
        return
    from .report.display import number, plus_minus, quantity

    _echo(f"{result.case.title}: P = {quantity(plan_result.push_force, 'N')} at alpha0 = "
          f"{quantity(plan_result.alpha0, 'rad')}, E_S = {quantity(plan_result.stored_energy, 'J')}")
    if plan_result.fuse is not None:
        ft = plan_result.fuse
        _table(f"Fuse and angle choices inside the target {ft.target[0] / 1e3:.6g} to {ft.target[1] / 1e3:.6g} kN "
               f"(rupture strength {ft.rupture_strength / 1e6:.4g} ± {ft.rupture_strength_std / 1e6:.3g} MPa)",
               [(number(1e3 * c.diameter, 4), number(c.alpha0, 4), plus_minus(c.push_force / 1e3, c.push_force_std / 1e3),
                 number(c.stored_energy), f"{100 * c.probability_within:.3g}%" + (" <- best" if c is ft.best else ""))
                for c in ft.choices if c.within],
               ("d [mm]", "alpha0 [rad]", "P [kN]", "E_S [J]", "P inside the target"))
        for text in ft.warnings:
            _echo(f"warning: {text}")
    m = plan_result.members
    _table(f"Member checks (fuse stress N4/A4 = {m.fuse_stress / 1e6:.4g} MPa)", [
        (c.member, c.check, number(c.demand / (1e6 if c.unit == 'Pa' else 1e3), 4),
         "-" if c.capacity is None else number(c.capacity / (1e6 if c.unit == 'Pa' else 1e3), 4),
         "MPa" if c.unit == "Pa" else "kN", "skipped" if c.utilisation is None else f"{c.utilisation:.3f}")
        for c in m.checks], ("member", "check", "demand", "capacity", "unit", "utilisation"))
    from .studies.planning import ENVELOPE_QUANTITIES

    env = plan_result.envelope
    from .report.display import unit_text

    _table(f"Release envelope: {env.friction} ({env.samples:,} sample(s))", [
        (label, unit_text(unit), number(env.nominal[k], 4), number(env.ranges[k]["p5"], 4),
         number(env.ranges[k]["p95"], 4), number(env.ranges[k]["max"], 4))
        for k, (unit, label) in ENVELOPE_QUANTITIES.items()],
        ("quantity", "unit", "nominal", "5%", "95%", "max"))
    if plan_result.clearance is not None:
        c = plan_result.clearance
        verdict = (f"CONTACT at {c.first_contact_time:.3g} s: {1e3 * c.margin_needed:.4g} mm more room needed"
                   if c.contact else "no contact")
        _echo(f"Clearance: d0 = {1e3 * c.d0:.4g} mm, largest approach {1e3 * c.max_approach:.4g} mm, "
                   f"{c.describe_minimum()}: {verdict}")
        if plan_result.clearance_spread is not None:
            sp = plan_result.clearance_spread
            p5 = "-" if sp["min_gap_p5_m"] is None else f"{1e3 * sp['min_gap_p5_m']:.4g}"
            _echo(f"  over {sp['clearance_samples']} friction samples: 5% of minimum gaps below "
                       f"{p5} mm, contact in {100 * sp['contact_share']:.3g}%")
    for text in plan_result.notes:
        _echo(f"note: {text}")
    if paths:
        _listing(paths, out)


@app.command()
@_guard
def bench(
    quick: Annotated[bool, typer.Option("--quick", help="Smaller samples; skip the 1e8-sample Dask run.")] = False,
    threads: Annotated[int | None, typer.Option("--threads", "-t", help="Threads of the all-cores measurement, 1 to the cores numba may use (default: all).")] = None,
    out: Annotated[Path | None, typer.Option("--out", "-o", show_default=False, help="Also write the results to this .json file (the --json keys) (default: none, print only).")] = None,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace the file --out names.")] = False,
    as_json: JsonOpt = False,
) -> None:
    """Benchmarks on the bench and the wide sample: kernel throughput on one core and on all, vs scipy (same run), accuracy vs mpmath (the error, and the backward error in input ulps: the error over the case's 1-ulp condition number), and whether the targets are met (speed per core; accuracy: median <= 1e-12, every case <= max(1e-10, 4 x its 1-ulp condition number))."""
    from .studies.bench import run_bench

    _check_threads(threads)
    _one_file(out, (".json",), overwrite)
    result = run_bench(quick=quick, threads=threads, log=lambda line: _echo(line, err=True))
    if out is not None:
        from .io.export import write_json

        write_json(result, out)
    if as_json:
        _print_json(result)
        return
    _bench_tables(result)
    if out is not None:
        _echo(f"Wrote 1 file: {out}")


def _bench_tables(result: dict[str, Any]) -> None:

    def e(x):  # an error to two digits, exponents written one way (7.8e-6)
        return "-" if x is None else f"{x:.1e}".replace("e-0", "e-").replace("e+0", "e").replace("e+", "e")

    def ulps(g):  # the backward error in input ulps: median, worst (two digits)
        if g["backward_max_ulps"] is None:
            return "-"
        return ", ".join(f"{x:.2g}".replace("e-0", "e-").replace("e+0", "e").replace("e+", "e")
                         for x in (g["backward_median_ulps"], g["backward_max_ulps"]))

    n = result["threads"]
    for sample in ("bench", "wide"):
        g = result[sample]
        st, idn = g["stop_time"], g["identify"]
        rows = [
            ("one core, wall [cases/s]", f"{st['cases_per_s']:,.0f}", f"{idn['cases_per_s']:,.0f}"),
            ("one core, CPU time [cases/s]", f"{st['cpu_cases_per_s']:,.0f}", f"{idn['cpu_cases_per_s']:,.0f}"),
            (f"{n} thread(s), wall [cases/s]", f"{st['all_cores_cases_per_s']:,.0f}",
             f"{idn['all_cores_cases_per_s']:,.0f}"),
            (f"{n} thread(s) / one core; same bytes", f"{st['all_cores_ratio']:.2f}x; {st['all_cores_identical']}",
             f"{idn['all_cores_ratio']:.2f}x; {idn['all_cores_identical']}"),
            ("scipy one case at a time [cases/s]", f"solve_ivp {st['solve_ivp_cases_per_s']:,.0f}",
             f"quad + brentq {idn['quad_brentq_cases_per_s']:,.1f}"),
            ("speed-up vs scipy", f"{st['speedup_vs_solve_ivp']:,.0f}x", f"{idn['speedup_vs_quad_brentq']:,.0f}x"),
            ("kernel error vs mpmath: median, worst", f"{e(st['median_rel_error'])}, {e(st['max_rel_error'])}",
             f"{e(idn['median_rel_error'])}, {e(idn['max_rel_error'])}"),
            ("1-ulp input sensitivity at the worst", e(st["worst_case_sensitivity_1ulp"]),
             e(idn["worst_case_sensitivity_1ulp"])),
            ("backward error [input ulps]: median, worst", ulps(st), ulps(idn)),
            ("scipy error vs mpmath: median, worst",
             f"{e(st['solve_ivp_median_rel_error'])}, {e(st['solve_ivp_max_rel_error'])}",
             f"{e(idn['quad_brentq_median_rel_error'])}, {e(idn['quad_brentq_max_rel_error'])}"),
            ("cases: kernels; accuracy vs mpmath", f"{st['cases']:,}; {st['accuracy_cases']}",
             f"{idn['cases']:,}; {idn['accuracy_cases']}"),
        ]
        _table(f"{sample} sample ({g['sample']})", rows, ("", "stop time t_F", "identification F1, F2"))
        if sample == "wide":  # one table per quantity: six columns fit 80 (ten did not: every cell cut)
            for key, what in (("stop_time", "stop time t_F"), ("identify", "identification F1, F2")):
                worst = g[key]["worst_stratum"]
                rows = [(a["stratum"], str(a["cases"]), e(a["median_rel_error"]), e(a["max_rel_error"]),
                         e(a["sensitivity_1ulp"]), ulps(a)) for a in g[key]["strata"]]
                _table(f"wide sample by stratum, {what} vs mpmath (worst in '{worst}'; backward error: the error "
                       "over the case's 1-ulp condition number, median and worst)", rows,
                       ("stratum", "cases", "median", "worst", "1-ulp sens.", "backward [ulps]"))
    import shutil
    import textwrap

    width = max(40, shutil.get_terminal_size((80, 24)).columns)  # long lines wrapped to the terminal, indented

    def echo(text: str, indent: int = 2) -> None:
        _echo(textwrap.fill(text, width=width, subsequent_indent=" " * indent))

    for t in result["targets"]:
        echo(f"{t['status']:>12}: {t['text']}", 14)
    gpu = result.get("gpu")
    if gpu is None:
        echo("GPU: none found (CuPy with a CUDA device; pip install 'quickrelease[gpu]'): the gpu backend not measured")
    else:
        rows = [(f"{sample}: on the device [cases/s]", f"{gpu[sample]['stop_time_cases_per_s']:,.0f}",
                 f"{gpu[sample]['identify_cases_per_s']:,.0f}") for sample in ("bench", "wide")]
        rows += [(f"{sample}: from host arrays [cases/s]", f"{gpu[sample]['stop_time_end_to_end_cases_per_s']:,.0f}",
                  f"{gpu[sample]['identify_end_to_end_cases_per_s']:,.0f}") for sample in ("bench", "wide")]
        rows += [(f"{sample}: max rel. difference from the CPU", e(gpu[sample]["stop_time_max_rel_diff"]),
                  f"ends {e(gpu[sample]['identify_ends_max_rel_diff'])}; F1 "
                  f"{gpu[sample]['identify_F1_max_diff_over_tolerance']:.2f} of its tolerance")
                 for sample in ("bench", "wide")]
        _table(f"gpu backend on {gpu['device']} (CuPy {gpu['cupy']}, float64)", rows,
               ("", "stop time t_F", "identification F1, F2"))
    if "uq_dask" in result:
        u = result["uq_dask"]
        echo(u["skipped"] if "skipped" in u else
             f"uq, 1e8 samples on {u['workers']} Dask workers: {u['wall_s']:.1f} s, peak memory "
             f"{u['peak_memory_GiB']:.2f} GiB")


def main() -> None:
    """Entry point of the ``quickrelease`` script."""
    try:
        app()
    except QuickReleaseError as exc:  # pragma: no cover - commands guard themselves
        _echo(f"error: {_clean(exc)}", err=True)
        sys.exit(2)


if __name__ == "__main__":
    main()
