"""The ``quickrelease`` command line (Typer).

Thin: parses quantities at the boundary (pint, via ``units.parse_quantity``), calls
the library, prints a table or one JSON object. Input errors print one line on
stderr and exit with code 2.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from functools import wraps
from pathlib import Path
from typing import Annotated, Any

import typer

from .errors import ParameterError, QuickReleaseError

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Dynamics of the pushing and quick-release device: simulate a release, identify friction.",
)

DeviceOpt = Annotated[Path | None, typer.Option("--device", help="Device TOML file (Table 2 keys); default: the paper's device.")]
ForceOpt = Annotated[str | None, typer.Option("--force", "-P", help="Push force P at release, e.g. '1598 kN' (SI number: N).")]
EnergyOpt = Annotated[str | None, typer.Option("--energy", help="Stored strain energy E_S, e.g. '2.90 kJ' (SI number: J).")]
Alpha0Opt = Annotated[str, typer.Option("--alpha0", help="Angle of the bars with the loading axis at release, e.g. '0.2' or '11.46 deg'.")]
MassOpt = Annotated[str, typer.Option("--mass-model", help="distributed (c = 2/3), lumped (c = 1) or a number c.")]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print one JSON object instead of a table.")]


def _fail(message: str) -> None:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=2)


def _guard(func: Callable[..., Any]) -> Callable[..., Any]:
    """Turn library input errors into one line on stderr and exit code 2."""

    @wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except QuickReleaseError as exc:
            _fail(str(exc))

    return wrapper


def _device(path: Path | None):
    from .device import load_device, preset

    return preset("paper") if path is None else load_device(path)


def _energy(device, force: str | None, energy: str | None, alpha0: float) -> tuple[float, float | None]:
    """E_S from --energy, or from --force by Eq. 2; returns (E_S, P or None)."""
    from .statics import strain_energy
    from .units import parse_quantity

    if (force is None) == (energy is None):
        raise ParameterError("--force/--energy", "both" if force else "neither", "exactly one of the two")
    if energy is not None:
        return parse_quantity(energy, "energy", "--energy"), None
    P = parse_quantity(force, "force", "--force")
    return strain_energy(P, alpha0, device).total, P


def _print_json(data: dict[str, Any]) -> None:
    typer.echo(json.dumps(data, indent=2, allow_nan=False))


def _table(title: str, rows: list[tuple[str, ...]], headers: tuple[str, ...]) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(title=title, title_justify="left")
    for h in headers:
        table.add_column(h)
    for row in rows:
        table.add_row(*row)
    Console(width=140).print(table)


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


@app.command()
@_guard
def simulate(
    device: DeviceOpt = None,
    force: ForceOpt = None,
    energy: EnergyOpt = None,
    alpha0: Alpha0Opt = ...,
    f1: Annotated[str, typer.Option("--f1", help="Friction at the central hinges F1, e.g. '420 N'.")] = "0",
    f2: Annotated[str, typer.Option("--f2", help="Friction at the rail supports F2, e.g. '0.8 kN'.")] = "0",
    mass_model: MassOpt = "distributed",
    method: Annotated[str, typer.Option("--method", help="energy, rk or explicit.")] = "energy",
    dt: Annotated[str | None, typer.Option("--dt", help="Time step of the explicit method, e.g. '1e-4 s'.")] = None,
    as_json: JsonOpt = False,
) -> None:
    """Simulate the release after the fuse breaks; print the stop time, final angle and peaks."""
    from .solvers import simulate as run
    from .units import parse_quantity

    dev = _device(device)
    a0 = parse_quantity(alpha0, "angle", "--alpha0")
    from ._validate import check_angle

    check_angle("alpha0", a0)
    E_S, P = _energy(dev, force, energy, a0)
    F1 = parse_quantity(f1, "force", "--f1")
    F2 = parse_quantity(f2, "force", "--f2")
    step = None if dt is None else parse_quantity(dt, "time", "--dt")
    response = run(E_S, a0, F1, F2, device=dev, mass_model=mass_model, method=method, dt=step)
    summary = {"push_force_N": P, **response.summary(), "device": dev.name}
    if as_json:
        _print_json(summary)
        return
    _table("Release", [(k, _fmt(v)) for k, v in summary.items()], ("quantity", "value"))


@app.command()
@_guard
def identify(
    device: DeviceOpt = None,
    force: ForceOpt = None,
    energy: EnergyOpt = None,
    alpha0: Alpha0Opt = ...,
    alpha_final: Annotated[str, typer.Option("--alpha-final", help="Observed final angle alpha_F, e.g. '0.7378 rad'.")] = ...,
    stop_time: Annotated[str, typer.Option("--stop-time", help="Observed time from release to stop t_F, e.g. '1.05 s'.")] = ...,
    mass_model: MassOpt = "distributed",
    as_json: JsonOpt = False,
) -> None:
    """Identify the friction forces F1, F2 from a test (Eq. 11-13, Table 7)."""
    from ._validate import check_angle
    from .identify import identify_friction
    from .units import parse_quantity

    dev = _device(device)
    a0 = parse_quantity(alpha0, "angle", "--alpha0")
    check_angle("alpha0", a0)
    E_S, P = _energy(dev, force, energy, a0)
    result = identify_friction(
        a0,
        parse_quantity(alpha_final, "angle", "--alpha-final"),
        parse_quantity(stop_time, "time", "--stop-time"),
        stored_energy=E_S,
        device=dev,
        mass_model=mass_model,
    )
    summary = {**result.summary(), "push_force_N": P, "device": dev.name}
    if as_json:
        _print_json(summary)
        return
    _table("Identified friction (Eq. 11-13)", [(k, _fmt(v)) for k, v in summary.items()], ("quantity", "value"))


@app.command()
@_guard
def demo(
    mass_model: MassOpt = "distributed",
) -> None:
    """The paper's test: E_S from Eq. 2 at P = 1598 kN, alpha0 = 0.2 rad; Table 7 identified; paper vs us."""
    from .device import preset
    from .paper import reproduce_table7

    dev = preset("paper")
    cmp = reproduce_table7(dev, mass_model=mass_model)
    typer.echo(f"Device: {dev.name} (Table 2); mass model: {mass_model}")
    terms = [(k, f"{v:.2f}") for k, v in cmp.E_S_breakdown.items()]
    terms.append(("total E_S", f"{cmp.E_S_eq2:.2f}"))
    _table("E_S by term (Eq. 2) [J]", terms, ("term", "J"))
    _table("Table 7: the paper and quickrelease", cmp.rows(), ("quantity", "paper", "quickrelease", "note"))
    typer.echo(
        f"Release with the identified friction: alpha_dot0 = {cmp.alpha_dot0:.4f} rad/s, "
        f"u_F = {cmp.u_final:.4f} m, v_F = {cmp.v_final:.4f} m, "
        f"peak u_dot = {cmp.peak_u_dot:.3f} m/s, peak v_dot = {cmp.peak_v_dot:.3f} m/s"
    )


def main() -> None:
    """Entry point of the ``quickrelease`` script."""
    try:
        app()
    except QuickReleaseError as exc:  # pragma: no cover - commands guard themselves
        typer.echo(f"error: {exc}", err=True)
        sys.exit(2)


if __name__ == "__main__":
    main()
