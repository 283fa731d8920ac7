"""Help texts for people (issue 22, items 25 and 27): the bare command prints its help once; no project-internal
words ("the targets of issue 12"); flags without a ``<bool>`` type beside them."""

from __future__ import annotations

import re

import pytest
import typer
from typer.testing import CliRunner

from quickrelease.cli import app

COMMANDS = sorted(typer.main.get_command(app).commands)


def test_no_arguments_prints_the_help_once():
    r = CliRunner().invoke(app, [], env={"COLUMNS": "120"})
    assert r.exit_code == 2
    assert r.stdout.count("Usage: ") == 1, r.stdout
    assert r.stdout.count("Commands") == 1 and r.stderr == ""
    assert all(f" {name} " in r.stdout for name in COMMANDS)


@pytest.mark.parametrize("command", ["", *COMMANDS])
def test_help_has_no_internal_words_and_no_bool_type_on_flags(command):
    r = CliRunner().invoke(app, [command, "--help"] if command else ["--help"], env={"COLUMNS": "200"})
    assert r.exit_code == 0, r.output
    text = r.stdout
    assert re.search(r"\bissue\b|\bitem \d|\bTODO\b", text, re.I) is None, text
    assert "<bool>" not in text
    assert re.search(r"--help\s+-h\s+Show this message", text), text  # the flag itself is still listed


def test_a_flag_help_row_keeps_its_text():
    r = CliRunner().invoke(app, ["run", "--help"], env={"COLUMNS": "120"})
    assert re.search(r"--json\s+Print one JSON object instead of a table", r.stdout), r.stdout
    assert re.search(r"--out\s+-o\s+<path>", r.stdout), r.stdout  # options that take a value keep their type
