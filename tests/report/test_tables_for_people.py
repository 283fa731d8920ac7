"""Tables for people (issue 11): every command's terminal output shows human names, rounded numbers with units,
no JSON keys (``push_force_N``), no 16-digit floats, no ``None``, no raw exponents (``1.6e+04``).

``bench`` (tests/studies/test_bench.py, on its tiny run), ``demo``, ``run``, ``report`` (tests/cli/test_cli.py) and ``uq``
(tests/studies/test_uq.py) are checked where their tests already run them."""

from pathlib import Path

import pytest
from quality import table_faults
from typer.testing import CliRunner

from quickrelease.cli import app

pytestmark = pytest.mark.usefixtures("few_band_draws")  # the bands' width is not looked at here

EXAMPLES = Path(__file__).parents[2] / "examples"
runner = CliRunner()

COMMANDS = {
    "simulate": ["simulate", "--force", "1598 kN", "--alpha0", "0.2"],
    "simulate-case": ["simulate", EXAMPLES / "larger_push.toml"],
    "identify": ["identify", "--energy", "2.90 kJ", "--alpha0", "0.2", "--alpha-final", "0.7378", "--stop-time",
                 "1.05"],
    "sweep": ["sweep", EXAMPLES / "larger_push.toml", "--grid", "force=500 kN:3000 kN:3", "--grid",
              "alpha0=0.1:0.5:3", "--out", "{tmp}/sweep.nc"],
    "synth": ["synth", EXAMPLES / "paper.toml", "--out", "{tmp}/rec.csv"],
    "synth-building": ["synth", EXAMPLES / "building.toml", "--building", "--out", "{tmp}/b.csv"],
    "fit": ["fit", EXAMPLES / "fit.toml"],
    "building": ["building", EXAMPLES / "building.toml"],
    "campaign": ["campaign", EXAMPLES / "campaign.toml"],
    "building-campaign": ["campaign", EXAMPLES / "building_campaign.toml"],
    "plan": ["plan", EXAMPLES / "plan.toml"],
}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n == "building-campaign" else n for n in COMMANDS])
def test_every_command_prints_tables_for_people(name, tmp_path):
    args = [str(a).replace("{tmp}", str(tmp_path)) for a in COMMANDS[name]]
    r = runner.invoke(app, args)
    assert r.exit_code == 0, r.output
    assert r.stdout.strip(), "nothing printed"
    assert table_faults(r.stdout) == []


def test_the_checker_finds_what_people_should_not_meet():
    """The checker itself: each fault of the old tables is found (issue 11's examples)."""
    assert table_faults("push_force_N 1.598e+06")  # a JSON key, a raw exponent
    assert table_faults("feasible stop times [0.9906441799358865, 1.2] s")  # 16 digits
    assert table_faults("stop time t_F  None")
    assert table_faults("friction 1.6e+04 N")
    assert not table_faults("note: column 'u_m' of 'rec.csv': 4 missing sample(s); push force P 1598 kN; "
                            "2.0e-5 s; 1,000,000 samples; 419.85 ± 0.40 N")


def test_the_display_helpers_round_as_results_are_quoted():
    """Hand-written expectations: the value rounded where its standard error (two digits) is, one SI prefix."""
    from quickrelease.report.display import estimate_row, interval, key_for, plus_minus, quantity

    assert plus_minus(420.023, 0.398, "N") == "420.02 ± 0.40 N"
    assert plus_minus(1.598e6, 3.9e4, "N") == "1598 ± 39 kN"
    assert plus_minus(223.0, 996.0, "N/rad") == "200 ± 1000 N/rad"
    assert plus_minus(2.1, None, "m/s^2") == "2.1 m/s²"
    assert quantity(1.598e6, "N") == "1598 kN" and quantity(None, "s") == "-"
    assert interval([0.99064418, 1.2139], "s") == "[0.99064, 1.2139] s"
    assert estimate_row("F1", 420.023, 0.398, (419.243, 420.803)) == (
        "hinge friction F1", "420.02 N", "0.40 N", "[419.24, 420.80] N")
    assert estimate_row("k1", 1.2345678e7, 2.3e5, (1.2e7, 1.3e7)) == (
        "initial stiffness k1", "12.35 MN/m", "0.23 MN/m", "[12.00, 13.00] MN/m")  # to the SE's 2 digits
    assert estimate_row("offset_a", 0.0012, 3e-5, None, "m/s^2")[0::3] == ("offset of a", "-")
    assert key_for("damping_ratio") == ("damping ratio zeta", "")
