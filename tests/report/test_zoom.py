"""The zoomable record figure of the HTML report (issue 24, item 3): the vendored uPlot inlined once, nothing
loaded from the network, every sample of the record in the page, the release and the stick marked, the static
figure kept for print and for readers without JavaScript; in headless Chromium (2 s; skipped where there is no
Chromium, but on CI): the figure draws without an error and its panels zoom, pan and reset together.

The record is made by the independent simulation of tests/building_reference.py (solve_ivp with events): its
stop time is the stick the figure must mark.
"""

import base64
import fnmatch
import io
import json
import math
import os
import re
import shutil
import subprocess
import tomllib
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
from building_reference import reference
from quality import html_faults

from quickrelease.building.isolation_fit import BuildingChannel
from quickrelease.report.building_plots import fit_figure
from quickrelease.report.html import render_building_report
from quickrelease.report.zoom import zoom_figure
from quickrelease.studies.building_analysis import analyse_building

pytestmark = pytest.mark.usefixtures("few_band_draws")  # the bands' width is not looked at here

ROOT = Path(__file__).resolve().parents[2]
VENDOR = ROOT / "src" / "quickrelease" / "report" / "vendor" / "uplot"
#: The building: 650 t, T = 2 s, 3% damping, sliders at 120 kN (they hold it about 3 s after the release).
M, T, ZETA, FS, D0, T_RELEASE = 6.5e5, 2.0, 0.03, 1.2e5, 0.15, 1.0
NOISE_X, NOISE_A = 1e-4, 0.01  # m, m/s^2


def _decode(text):
    return np.frombuffer(base64.b64decode(text), dtype="<f4")


def _times(spec):
    """The page's time axis, decoded as zoom.js does."""
    if "offsets" in spec:
        return spec["t0"] + _decode(spec["offsets"]).astype(float)
    return np.concatenate([spec["t0"] + spec["dt"] * (first + np.arange(n)) for first, n in spec["runs"]])


def _data(page, ident):
    found = re.search(rf'<script type="application/json" id="{ident}-data">(.*?)</script>', page, re.S)
    assert found, f"no data of {ident} in the page"
    return json.loads(found.group(1))


@pytest.fixture(scope="module")
def building(tmp_path_factory):
    """(result, report text, report path, the reference's stop time [s after the release], x, a) of a 8 s
    record: x at 100 Hz with 3 samples dropped, a at 50 Hz on its own clock."""
    k = M * (2 * math.pi / T) ** 2
    c = 2 * ZETA * math.sqrt(k * M)
    rng = np.random.default_rng(1)
    tx = np.delete(np.arange(0.0, 8.0, 0.01), [150, 151, 420])
    ta = np.arange(0.0, 8.0, 0.02) + 0.0037
    x, stop = reference(M, k, k, math.inf, c, FS, D0, tx - T_RELEASE)
    x = x + rng.normal(0, NOISE_X, tx.size)
    a = reference(M, k, k, math.inf, c, FS, D0, ta - T_RELEASE, with_rates=True)[0][2] + rng.normal(0, NOISE_A, ta.size)
    result = analyse_building(channels=[BuildingChannel("x", "x", tx, x), BuildingChannel("a", "a", ta, a)], mass=M)
    buf = io.StringIO()
    fit_figure(result).savefig(buf, format="svg")
    page = render_building_report(result, {"building_fit": buf.getvalue()}, "Zoom test",
                                  provenance={"quickrelease": "test", "input": None})
    path = tmp_path_factory.mktemp("zoom") / "report.html"
    path.write_text(page, encoding="utf-8")
    return result, page, path, stop, (tx, x), (ta, a)


@pytest.fixture(scope="module")
def device():
    """(result, report text) of examples/fit.toml: the device's fit to a 500 Hz record of u, v and a_head."""
    from quickrelease.io.case import load_case
    from quickrelease.report.html import render_report
    from quickrelease.report.plots import fit_figure as device_fit_figure
    from quickrelease.workflow import run_case

    result = run_case(load_case(ROOT / "examples" / "fit.toml"))
    buf = io.StringIO()
    device_fit_figure(result.fit).savefig(buf, format="svg")
    return result, render_report(result, {"fit_channels": buf.getvalue()})


def test_the_device_fit_zooms_with_every_sample_and_the_stop(device):
    result, page = device
    data = _data(page, "fit_channels")
    columns = np.genfromtxt(ROOT / "examples" / "records" / "paper_500Hz.csv", delimiter=",", skip_header=1)
    assert [(c["name"], c["unit"]) for c in data["channels"]] == [("u", "m"), ("v", "m"), ("a_head", "m/s²")]
    for k, ch in enumerate(data["channels"]):
        kept = np.isfinite(columns[:, 1 + k])  # the record's empty cells are no samples
        assert np.array_equal(_decode(ch["values"]), columns[kept, 1 + k].astype("<f4")), ch["name"]
        assert np.max(np.abs(_times(ch["t"]) - columns[kept, 0])) < 1e-6  # jittered clock: float32 offsets
    marks = {m["label"]: m["t"] for m in data["markers"]}
    assert marks["stop t_F"] - marks["release"] == pytest.approx(1.05, abs=0.01)  # Table 7's stop time
    assert page.count("<script>/*! uPlot") == 1


def test_every_sample_is_in_the_page(building):
    result, page, _, _, (tx, x), (ta, a) = building
    data = _data(page, "building_fit")
    x_page, a_page = data["channels"]
    assert (x_page["name"], x_page["unit"], a_page["name"], a_page["unit"]) == ("x", "m", "a", "m/s²")
    # the record itself, as float32: every sample, the dropped ones left out of the grid's runs
    assert np.array_equal(_decode(x_page["values"]), x.astype("<f4"))
    assert np.array_equal(_decode(a_page["values"]), a.astype("<f4"))
    assert x_page["t"]["runs"] == [[0, 150], [152, 268], [421, 379]]
    assert np.max(np.abs(_times(x_page["t"]) - tx)) < 1e-12 and np.max(np.abs(_times(a_page["t"]) - ta)) < 1e-12
    # the residuals are the noise the record was made with; the model spans the record
    for ch, noise in ((x_page, NOISE_X), (a_page, NOISE_A)):
        resid = _decode(ch["residual"])
        assert resid.size == _decode(ch["values"]).size and 0.8 * noise < np.std(resid) < 1.25 * noise, ch["name"]
        assert 0.8 * noise < ch["sigma"] < 1.25 * noise
        model_t = _times(ch["model_t"])
        assert model_t[0] <= 0.0037 and model_t[-1] >= 7.98 and _decode(ch["model"]).size == model_t.size


def test_the_release_and_the_stick_are_marked(building):
    result, page, _, stop, _, _ = building
    marks = {m["label"]: m["t"] for m in _data(page, "building_fit")["markers"]}
    assert set(marks) == {"release", "stick"}
    assert marks["release"] == pytest.approx(T_RELEASE, abs=0.005)
    assert marks["stick"] == pytest.approx(T_RELEASE + stop, abs=0.01)  # the reference's stop, 3.0 s after


def test_uplot_is_inlined_once_and_the_page_loads_nothing(building):
    _, page, _, _, _, _ = building
    library = (VENDOR / "uPlot.iife.min.js").read_text(encoding="utf-8").strip()
    assert page.count(library) == 1 and (VENDOR / "uPlot.min.css").read_text(encoding="utf-8").strip() in page
    assert "MIT License" in (VENDOR / "LICENSE").read_text() and "MIT licence" in page  # named where it is used
    assert html_faults(page) == []

    class Loads(HTMLParser):
        def __init__(self):
            super().__init__()
            self.loads, self.tags = [], set()

        def handle_starttag(self, tag, attrs):
            self.tags.add(tag)
            self.loads += [v for k, v in attrs if k in ("src", "href", "xlink:href", "data", "action") and v
                           and not v.startswith("#")]

    parser = Loads()
    parser.feed(page)
    assert parser.loads == [] and not parser.tags & {"link", "img", "iframe", "object", "embed"}
    lowered = page.lower()
    for fetch in ("@import", "url(http", "url(//", "fetch(", "xmlhttprequest", "websocket", "import("):
        assert fetch not in lowered, fetch
    # no address but uPlot's banner comment, outside the static SVG (whose namespaces are names, not loads)
    outside = re.sub(r"<svg.*?</svg>", "", page, flags=re.S)
    assert re.findall(r"https?://[^\s\"')]*|//[a-z0-9.-]+\.[a-z]{2,}/", outside) == ["https://github.com/leeoniya/uPlot"]


def test_the_static_figure_stays_for_print_and_without_javascript(building):
    _, page, _, _, _, _ = building
    assert '<figure id="building_fit"><svg' in page  # the figure as before, its zoomable twin after it
    assert page.index('id="building_fit-zoom"') > page.index("</svg>", page.index('<figure id="building_fit">'))
    css = page.split("<style>", 1)[1].split("</style>", 1)[0]
    assert "figure.qr-live > svg { display: none; }" in css  # hidden only once the script has drawn every panel
    assert "@media print { figure.qr-live > svg { display: inline; } .qr-zoom { display: none; } }" in css
    assert 'class="qr-live"' not in page


def test_a_page_without_a_record_figure_carries_no_script():
    from quickrelease.report.html import _page

    page = _page("t", ["<p>no record, a note naming data-qr-zoom=&quot;x&quot;</p>"])
    assert "<script" not in page and "uPlot" not in page


def test_user_text_in_the_data_cannot_end_the_script():
    name = "</script><script>alert(1)</script>"
    t = np.arange(5) * 0.1
    html = zoom_figure("f", [{"name": name, "unit": "m", "t": t, "values": t, "residual": 0 * t, "sigma": 1.0,
                              "model_t": t, "model": t}], [("release", 0.1), ("stick", math.inf)])
    assert html.count("</script>") == 1 and "<script>alert" not in html
    data = _data(html, "f")
    assert data["channels"][0]["name"] == name and data["markers"] == [{"label": "release", "t": 0.1}]


@pytest.mark.parametrize(("t", "expected"), [
    ([0.0, 0.01, 0.02, 0.04, 0.05], {"t0": 0.0, "dt": 0.01, "runs": [[0, 3], [4, 2]]}),
    ([2.0, 2.5, 3.0], {"t0": 2.0, "dt": 0.5, "runs": [[0, 3]]}),
    ([0.0, 0.01, 0.025, 0.03], None),  # off the grid: float32 offsets
])
def test_time_axes(t, expected):
    from quickrelease.report.zoom import _times as encode

    spec = encode(np.array(t))
    if expected is None:
        assert set(spec) == {"t0", "offsets"}
    else:
        assert spec["runs"] == expected["runs"] and spec["t0"] == expected["t0"]
        assert spec["dt"] == pytest.approx(expected["dt"], rel=1e-12)
    assert np.max(np.abs(_times(spec) - np.array(t))) < 1e-9


def test_the_package_ships_the_library():
    """The wheel's package data (pyproject) holds the driver and the vendored files."""
    globs = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]["quickrelease"]
    package = ROOT / "src" / "quickrelease"
    for path in [package / "report" / "zoom.js", *VENDOR.iterdir()]:
        rel = path.relative_to(package).as_posix()
        assert any(fnmatch.fnmatch(rel, g) and rel.count("/") == g.count("/") for g in globs), rel


# -- in a browser ---------------------------------------------------------------------------------------------

#: Put first in <head>: every error of the page (thrown or printed with console.error) collected.
_CATCH = """<script>window.__errors = [];
window.addEventListener("error", function (e) { __errors.push(String(e.message)); });
(function () { var ce = console.error; console.error = function () {
  __errors.push(Array.prototype.join.call(arguments, " ")); ce.apply(console, arguments); }; })();</script>"""

#: Put last in <body>: drive the figure ``FIGURE`` through uPlot's API and the pointer, write what happened into
#: the page. The zoom: the fifth tenth of the record, on the first panel.
_PROBE = """<script>(function () {
function out(o) { var e = document.createElement("pre"); e.id = "probe-" + "out"; e.textContent = JSON.stringify(o);
  document.body.appendChild(e); }
function xs(f) { return f.charts.map(function (u) { return [u.scales.x.min, u.scales.x.max]; }); }
function later(fn) { setTimeout(fn, 30); }
var o = {errors: __errors}, id = "FIGURE";
try {
  var f = window.quickreleaseZoom[id];
  o.canvases = document.querySelectorAll("#" + id + "-zoom canvas").length;
  o.figureClass = document.getElementById(id).className;
  o.svgShown = getComputedStyle(document.querySelector("#" + id + " > svg")).display;
  o.full = xs(f); o.yFull = f.charts[0].scales.y.max - f.charts[0].scales.y.min;
  o.residualData = f.charts[1].data;  // the first channel's residuals as the page decoded them
  var a = f.full.min, span = f.full.max - f.full.min;
  var box = f.charts[0].over, b = box.getBoundingClientRect();  // drag a box over the middle half of the first panel
  function mouse(type, x) { return new MouseEvent(type, {bubbles: true, button: 0, clientX: b.left + x * b.width,
                                                         clientY: b.top + 10, movementX: 1}); }  // moved: a drag
  box.dispatchEvent(mouse("mouseenter", 0.25)); box.dispatchEvent(mouse("mousedown", 0.25));
  later(function () { box.dispatchEvent(mouse("mousemove", 0.75)); });
  setTimeout(function () { box.dispatchEvent(mouse("mouseup", 0.75)); }, 60);
  setTimeout(function () {
  o.dragged = xs(f);
  f.charts[0].setScale("x", {min: a + 0.4 * span, max: a + 0.5 * span});  // uPlot's API, on the first panel only
  later(function () {
    o.zoomed = xs(f); o.yZoomed = f.charts[0].scales.y.max - f.charts[0].scales.y.min;
    var last = f.charts[f.charts.length - 1], over = last.over, r = over.getBoundingClientRect();
    over.dispatchEvent(new MouseEvent("mousedown", {bubbles: true, shiftKey: true, button: 0,
                                                    clientX: r.left + r.width / 2, clientY: r.top + 5}));
    document.dispatchEvent(new MouseEvent("mousemove", {bubbles: true, clientX: r.left + r.width / 4,
                                                        clientY: r.top + 5}));
    document.dispatchEvent(new MouseEvent("mouseup", {bubbles: true, clientX: r.left + r.width / 4}));
    later(function () {
      o.panned = xs(f);
      over = f.charts[1].over; r = over.getBoundingClientRect();
      over.dispatchEvent(new WheelEvent("wheel", {bubbles: true, cancelable: true, deltaY: -100,
                                                  clientX: r.left + r.width / 2, clientY: r.top + 5}));
      later(function () {
        o.plainWheel = xs(f);  // a wheel without Shift scrolls the page, not the figure
        over.dispatchEvent(new WheelEvent("wheel", {bubbles: true, cancelable: true, shiftKey: true, deltaY: -100,
                                                    clientX: r.left + r.width / 2, clientY: r.top + 5}));
        later(function () {
          o.wheeled = xs(f);
          f.charts[1].over.dispatchEvent(new MouseEvent("dblclick", {bubbles: true, button: 0}));
          later(function () { o.reset = xs(f); out(o); });
        });
      });
    });
  });
  }, 90);
} catch (err) { o.errors.push("probe: " + err); out(o); }
})();</script>"""


def _chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        if shutil.which(name):
            return shutil.which(name)
    return None


def _in_chromium(page: str, figure: str, folder: Path) -> dict:
    """Open ``page`` (with the probes, on its figure ``figure``) in headless Chromium; what the probe wrote."""
    browser = _chromium()
    if browser is None:
        if os.environ.get("CI"):
            pytest.fail("chromium is not installed; .ci/run installs it")
        pytest.skip("chromium not installed (apt-get install chromium)")
    probed = folder / "probed.html"
    probed.write_text(page.replace("<head>", "<head>" + _CATCH, 1).replace("</body>", _PROBE.replace("FIGURE", figure) + "</body>", 1),
                      encoding="utf-8")
    cmd = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           f"--user-data-dir={folder / 'profile'}", "--window-size=1200,2000", "--virtual-time-budget=10000",
           "--dump-dom", probed.as_uri()]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=120, check=False)
    found = re.search(r'<pre id="probe-out">(.*?)</pre>', run.stdout, re.S)
    assert found, ("the probe wrote nothing", run.stdout[-2000:], run.stderr[-2000:])
    return json.loads(found.group(1).replace("&lt;", "<").replace("&gt;", ">").replace("&amp;", "&"))


@pytest.mark.slow
@pytest.mark.parametrize(("case", "figure", "channels"), [("building", "building_fit", 2), ("device", "fit_channels", 3)])
def test_the_figure_zooms_pans_and_resets_in_headless_chromium(case, figure, channels, request, tmp_path):
    page = request.getfixturevalue(case)[1]
    o = _in_chromium(page, figure, tmp_path)
    assert o["errors"] == []
    assert o["canvases"] == 2 * channels  # each channel a panel and its residuals
    assert o["figureClass"] == "qr-live" and o["svgShown"] == "none"  # drawn: the static figure steps aside
    data = _data(page, figure)
    ends = [f(_times(c[key])) for c in data["channels"] for key in ("t", "model_t") for f in (np.min, np.max)]
    t0, t1 = min(ends), max(ends)
    assert np.allclose(o["full"], [[t0, t1]] * 2 * channels, rtol=0, atol=1e-9)
    first = data["channels"][0]  # decoded in the page as here: every time and residual of the first channel
    assert np.allclose(o["residualData"][0], _times(first["t"]), rtol=0, atol=1e-9)
    assert np.array_equal(np.array(o["residualData"][1], dtype="<f4"), _decode(first["residual"]))
    span = t1 - t0
    # a box dragged over the middle half of the first panel: every panel shows that half
    assert np.allclose(o["dragged"], [[t0 + 0.25 * span, t0 + 0.75 * span]] * 2 * channels, rtol=0,
                       atol=0.003 * span)
    # the first panel zoomed through uPlot's API: every panel follows; its y axis fits the samples in view
    lo, hi = t0 + 0.4 * span, t0 + 0.5 * span
    assert np.allclose(o["zoomed"], [[lo, hi]] * 2 * channels, rtol=0, atol=1e-9) and o["yZoomed"] < 0.9 * o["yFull"]
    # Shift + drag a quarter of the width to the left on the last panel: the time axis moves a quarter later
    assert np.allclose(o["panned"], [[lo + 0.025 * span, hi + 0.025 * span]] * 2 * channels, rtol=0,
                       atol=0.002 * span)
    assert o["plainWheel"] == o["panned"]
    # Shift + wheel up in the middle of the second panel: a 0.75 times narrower window about its centre
    (lo2, hi2), = set(map(tuple, o["wheeled"]))
    assert hi2 - lo2 == pytest.approx(0.075 * span, rel=1e-6)
    assert (lo2 + hi2) / 2 == pytest.approx((lo + hi) / 2 + 0.025 * span, abs=0.002 * span)
    assert o["reset"] == o["full"]  # a double click: the whole record, everywhere
