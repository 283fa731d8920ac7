"""User text in any language, with TOML/JSON/HTML/mathtext metacharacters and terminal escape sequences, passes
through every writer (NetCDF, CSV, JSON, HTML, SVG, the TOML of ``synth --case-out``) and never reaches the
terminal as an escape sequence (issue 9, item 6).

The case files are written here with ``json.dumps(..., ensure_ascii=False)``, which is also a valid TOML basic
string (JSON's escapes are a subset of TOML's), so the test does not share the package's TOML writer.
"""

import html
import json
import tomllib
import xml.dom.minidom
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from typer.testing import CliRunner

from quickrelease.cli import app

EXAMPLES = Path(__file__).parents[2] / "examples"

#: Umlaut, CJK, an emoji; a valid and an invalid mathtext formula (an even number of '$': matplotlib would parse
#: it as math and fail on '$^$'); an XML comment breaker;
#: a backslash, a quote, a newline; an ANSI colour (CSI) and an OSC window-title sequence ended by BEL.
NAME = 'Prüfung 試験 $x$ $^$ -- \\ " \n \x1b[31m \x1b]0;pwn\x07 🎉'
#: What a figure or a terminal shows of NAME: every control character but newline as '?'.
SHOWN = NAME.replace("\x1b", "?").replace("\x07", "?")

runner = CliRunner()


def cli(*args):
    r = runner.invoke(app, [str(a) for a in args])
    assert r.exit_code == 0, r.output
    assert "\x1b" not in r.output and "\x07" not in r.output and "\x9b" not in r.output
    return r


def _toml(text: str) -> str:
    return json.dumps(text, ensure_ascii=False)


def _case(tmp_path: Path, title: str) -> Path:
    text = (EXAMPLES / "paper.toml").read_text(encoding="utf-8")
    text = text.replace('title = "Paper test: Table 7 (Oliveto et al.)"', f"title = {_toml(title)}", 1)
    assert _toml(title) in text
    path = tmp_path / "case.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _strings(data) -> list[str]:
    """Every string in a JSON document."""
    if isinstance(data, dict):
        return [s for v in data.values() for s in _strings(v)]
    if isinstance(data, list):
        return [s for v in data for s in _strings(v)]
    return [data] if isinstance(data, str) else []


def _svg_ok(path: Path) -> str:
    text = path.read_text(encoding="utf-8")
    xml.dom.minidom.parseString(text.encode("utf-8"))  # well-formed XML: no control character, no '--' in a comment
    return text


@pytest.mark.slow
def test_run_and_report_carry_the_title(tmp_path):
    xr = pytest.importorskip("xarray")
    case = _case(tmp_path, NAME)
    out = tmp_path / "out \x1b[31m red \x1b]0;title\x07"  # a folder name that the run prints back
    cli("run", case, "--out", out)
    with xr.open_dataset(out / "timeseries.nc") as ds:  # the title round-trips through NetCDF, letter for letter
        assert ds.attrs["case"] == NAME
        assert ds["t"].size > 100
    assert (out / "timeseries.csv").read_text(encoding="utf-8").startswith("t_s,")
    manifest = json.loads((out / "manifest.json").read_text(encoding="utf-8"))
    assert NAME in _strings(manifest)
    page = (out / "report.html").read_text(encoding="utf-8")
    assert html.escape(NAME.split("\n")[0], quote=True) in page
    assert "<script" not in page and '" \n' not in page  # the quote is escaped
    for svg in (out / "figures").glob("*.svg"):
        _svg_ok(svg)
    cli("report", case, "--out", tmp_path / "rep")
    assert html.escape("Prüfung 試験 $x$ $^$", quote=True) in (tmp_path / "rep" / "report.html").read_text(encoding="utf-8")


@pytest.mark.slow  # (1.1-1.5 s of fits: the README's quick run stays under 3 minutes; CI runs it)
def test_campaign_names_and_title_in_every_output(tmp_path):
    text = (EXAMPLES / "campaign.toml").read_text(encoding="utf-8")
    text = text.replace('name = "T1"', f"name = {_toml(NAME)}", 1)
    text = text.replace('title = "Friction campaign on the paper\'s device (synthetic)"', f"title = {_toml(NAME)}", 1)
    text = text.replace('record = "records/', f'record = "{(EXAMPLES / "records").as_posix()}/')
    path = tmp_path / "campaign.toml"
    path.write_text(text, encoding="utf-8")
    assert tomllib.loads(text)["tests"][0]["name"] == NAME
    r = cli("campaign", path, "--out", tmp_path / "out")
    assert "Prüfung 試験 $x$ $^$" in r.stdout and "?[31m" in r.stdout  # shown, with the escape made harmless
    out = tmp_path / "out"
    data = json.loads((out / "campaign.json").read_text(encoding="utf-8"))
    assert data["title"] == NAME
    assert data["tests"][0]["name"] == NAME
    svg = _svg_ok(out / "figures" / "campaign_friction.svg")
    # the figures keep text as SVG text (svg.fonttype "none"): each line of the name is a text element
    texts = {"".join(node.itertext()) for node in ET.fromstring(svg.encode("utf-8")).iter("{http://www.w3.org/2000/svg}text")}
    for line in SHOWN.split("\n"):
        assert line in texts, (line, texts)
    assert (out / "figures" / "campaign_friction.png").stat().st_size > 1000
    page = (out / "report.html").read_text(encoding="utf-8")
    assert html.escape("Prüfung 試験 $x$ $^$ --", quote=True) in page
    from quality import report_number_faults

    assert report_number_faults(page) == []


def test_synth_case_out_is_valid_toml_for_any_file_name(tmp_path):
    folder = tmp_path / 'd Prüfung $x$ " \\ q'
    folder.mkdir()
    record = folder / 'rec $1 "試験" \\ \x1b[31m.csv'
    case_out = folder / "case.toml"
    cli("synth", EXAMPLES / "paper.toml", "--rate", "200 Hz", "--out", record, "--case-out", case_out)
    case = tomllib.loads(case_out.read_text(encoding="utf-8"))
    assert case["title"] == f"Fit to {record.name}"
    assert (case_out.parent / case["record"]["file"]).resolve() == record.resolve()
    header = record.read_text(encoding="utf-8").splitlines()[0]
    assert header.startswith("t_s,")
