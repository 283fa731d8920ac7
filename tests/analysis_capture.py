"""Run a command of the CLI and keep what ``analyse_building`` returned on its way to it (the fit made once, for the
tests that look at both the command's output and the analysis behind it)."""

from __future__ import annotations

from typing import Any

import pytest
from typer.testing import CliRunner


def invoke_keeping_analysis(args: list[str]) -> tuple[Any, list[Any]]:
    """``quickrelease <args>`` through typer's CliRunner, with :func:`quickrelease.studies.building_analysis.
    analyse_building` wrapped to keep each of its returns: (the runner's result, the returns in call order). The
    wrapper is undone when the command ends."""
    import quickrelease.studies.building_analysis as analysis
    from quickrelease.cli import app

    real, kept = analysis.analyse_building, []

    def keep(*a, **kw):
        kept.append(real(*a, **kw))
        return kept[-1]

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(analysis, "analyse_building", keep)
        result = CliRunner().invoke(app, args)
    return result, kept
