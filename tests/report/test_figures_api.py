"""Figures as a library user composes them (issue 11): the user's matplotlib settings untouched, figures
drawn into the user's own Figure, text kept as text in SVG, no repeated ids in a report."""

import re
from collections import Counter

import matplotlib
import pytest

from quickrelease import simulate
from quickrelease.report import plots
from quickrelease.workflow import run_case, write_results


@pytest.fixture(scope="module")
def response():
    return simulate(2900.0, 0.2, 419.85, 804.57)


def test_figure_functions_leave_rcparams_alone(response):
    before = dict(matplotlib.rcParams)
    with matplotlib.rc_context({"font.size": 17, "axes.grid": False}):
        fig = plots.fig13(response)
        assert matplotlib.rcParams["font.size"] == 17  # the user's setting still holds inside their context
    assert dict(matplotlib.rcParams) == before
    # ... while the figure itself is drawn in the package's style
    assert fig.axes[0].title.get_fontsize() == 9


def test_draw_into_a_users_figure_or_subfigure(response):
    from matplotlib.figure import Figure

    mine = Figure(figsize=(10, 4))
    left, right = mine.subfigures(1, 2)
    assert plots.fig14(response, fig=left) is left
    assert plots.fig15(response, fig=right) is right
    assert len(mine.axes) == 3  # fig14's two panels and fig15's one, in the user's figure
    assert mine.get_size_inches().tolist() == [10, 4]


def test_svg_text_is_text_and_report_ids_are_unique(tmp_path):
    from quickrelease.io.case import load_case

    paths = write_results(run_case(load_case("examples/paper.toml")), tmp_path / "out")
    assert paths
    svg = (tmp_path / "out" / "figures" / "fig13_response.svg").read_text(encoding="utf-8")
    assert "<text" in svg and "position angle" in svg.lower()  # a label as text, not as glyph paths
    html = (tmp_path / "out" / "report.html").read_text(encoding="utf-8")
    ids = Counter(re.findall(r'\bid="([^"]+)"', html))
    repeated = {k: n for k, n in ids.items() if n > 1}
    assert not repeated, repeated
    # every local reference points at an id of the page
    refs = set(re.findall(r"url\(#([^)]+)\)", html)) | set(re.findall(r'href="#([^"]+)"', html))
    assert refs <= set(ids), refs - set(ids)
