"""Result objects in a notebook (issue 11): a short repr (never the whole device), an HTML table."""

import xml.etree.ElementTree as ET

import pytest

import quickrelease as qr
from quickrelease._results import Summarised
from quickrelease.io.case import load_case
from quickrelease.workflow import run_case


@pytest.fixture(scope="module")
def results():
    ident = qr.identify_friction(0.2, 0.7378, 1.05, stored_energy=2900.0)
    response = qr.simulate(2900.0, 0.2, 419.85, 804.57)
    case = run_case(load_case("examples/paper.toml"))
    return {"identification": ident, "response": response, "case": case}


def test_short_reprs(results):
    ident = results["identification"]
    text = repr(ident)
    assert text.startswith("Identification(F1=") and "Device" not in text and len(text) < 160
    assert "F1=419.85 N" in text  # hand-checked digits of the paper case (README: 419.85 N)
    for obj in results.values():
        assert isinstance(obj, Summarised)
        assert len(repr(obj)) < 200 and "array(" not in repr(obj) and "\n" not in repr(obj)


def test_html_tables_are_well_formed(results):
    for obj in results.values():
        page = obj._repr_html_()
        root = ET.fromstring(page)  # well-formed: a notebook renders it
        assert root.tag == "table" and len(root.findall("tr")) == len(obj.summary())
