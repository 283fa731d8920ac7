"""Render every command's ``--help`` of the Typer app into ``cli.rst`` at build time.

sphinx-click does not know Typer's rich help, so each command's help is produced the way a user sees it
(``quickrelease CMD --help`` on an 100-column terminal without colour) and written into a literal block;
the page is regenerated on every build, so the reference cannot drift from the code.
"""

from __future__ import annotations

import os
from pathlib import Path

HEADER = """\
Command-line reference
======================

Every command's ``--help``, rendered from the command line of this version at build time.
The user guide explains each in context; all quantities take a bare SI number or a string with units.

"""


def command_names() -> list[str]:
    import typer

    from quickrelease.cli import app

    return list(typer.main.get_command(app).commands)  # the order of ``quickrelease --help``


def render_help(args: list[str]) -> str:
    from typer.testing import CliRunner

    from quickrelease.cli import app

    result = CliRunner().invoke(app, [*args, "--help"], env={"COLUMNS": "100", "NO_COLOR": "1", "TERM": "dumb"},
                                color=False, prog_name="quickrelease")
    if result.exit_code != 0:
        raise RuntimeError(f"quickrelease {' '.join(args)} --help exited with {result.exit_code}: {result.output}")
    return "\n".join(line.rstrip() for line in result.output.splitlines()).strip("\n")


def render_page() -> str:
    parts = [HEADER]
    parts.append(".. _cli-quickrelease:\n\n``quickrelease``\n----------------\n\n.. code-block:: text\n\n")
    parts.append(_indent(render_help([])) + "\n\n")
    for name in command_names():
        title = f"``quickrelease {name}``"
        parts.append(f".. _cli-{name}:\n\n{title}\n{'-' * len(title)}\n\n.. code-block:: text\n\n")
        parts.append(_indent(render_help([name])) + "\n\n")
    return "".join(parts)


def _indent(text: str) -> str:
    return "\n".join(("   " + line) if line.strip() else "" for line in text.splitlines())


def _generate(app) -> None:
    target = Path(app.srcdir) / "cli.rst"
    text = render_page()
    if not target.exists() or target.read_text(encoding="utf-8") != text:  # unchanged: no rebuild
        target.write_text(text, encoding="utf-8")


def setup(app):
    os.environ.setdefault("COLUMNS", "100")
    app.connect("builder-inited", _generate)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
