"""Exports, figures and the HTML report (issue: interfaces)."""

import json
import os
import shutil
import struct
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from conftest import mp_identify

from quickrelease import simulate
from quickrelease.io.case import load_case
from quickrelease.io.export import atomic_path, read_csv, read_netcdf, write_csv, write_json, write_netcdf
from quickrelease.workflow import FIGURES, run_case, write_results

EXAMPLES = Path(__file__).parents[2] / "examples"
#: The figures of the paper case (no record, no plan: see test_fit.py and test_planning.py for those).
PAPER_FIGURES = [stem for stem in FIGURES if stem != "fit_channels" and not stem.startswith(("plan_", "building_"))]


@pytest.fixture(scope="module")
def paper_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    result = run_case(load_case(EXAMPLES / "paper.toml"))
    return result, write_results(result, out), out


def png_size(path):
    with open(path, "rb") as fh:
        head = fh.read(24)
    assert head[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", head[16:24])


def test_csv_round_trip_is_exact(tmp_path):
    r = simulate(2900.0, 0.2, 419.85, 804.57, method="rk", t_end=1.2)
    path = write_csv(r, tmp_path / "r.csv")
    back = read_csv(path)
    header = path.read_text().splitlines()[0].split(",")
    assert header[:3] == ["t_s", "alpha_rad", "alpha_dot_rad_s"]
    for key, values in r.to_dict().items():
        assert np.array_equal(back[key], values), key


def test_netcdf_round_trip(tmp_path):
    r = simulate(2900.0, 0.2, 419.85, 804.57)
    back = read_netcdf(write_netcdf(r, tmp_path / "r.nc"))
    assert np.array_equal(back["alpha"], r.alpha) and np.array_equal(back["v_dot"], r.v_dot)
    from scipy.io import netcdf_file

    with netcdf_file(tmp_path / "r.nc", "r", mmap=False) as f:
        assert f.variables["u_dot"].units == b"m/s"
        assert float(f.stop_time_s) == r.stop_time


def test_netcdf_through_xarray_has_a_time_coordinate_and_cf_attributes(tmp_path):
    import xarray as xr

    from quickrelease import __version__

    r = simulate(2900.0, 0.2, 419.85, 804.57)
    write_netcdf(r, tmp_path / "r.nc")
    with xr.open_dataset(tmp_path / "r.nc") as ds:
        assert ds.alpha.dims == ("t",) and np.array_equal(ds.t.values, r.t)  # alpha.plot() is against time
        assert ds.t.attrs["units"] == "s" and ds.u_ddot.attrs["units"] == "m/s^2"
        assert all("long_name" in ds[v].attrs for v in [*ds.data_vars, "t"])
        assert ds.attrs["Conventions"].startswith("CF-") and ds.attrs["source"] == f"quickrelease {__version__}"
        assert ds.attrs["stop_time_s"] == r.stop_time


def test_atomic_write_leaves_nothing_on_failure(tmp_path):
    target = tmp_path / "out.json"
    write_json({"a": 1}, target)
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_text('{"a": 2, "half')
            raise RuntimeError("interrupted")
    assert json.loads(target.read_text()) == {"a": 1}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.json"]
    assert oct(target.stat().st_mode & 0o777) == oct(0o666 & ~_umask())


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_run_writes_everything(paper_run):
    result, paths, out = paper_run
    names = {p.relative_to(out).as_posix() for p in paths.values()}
    expected = {"summary.json", "identification.json", "timeseries.csv", "timeseries.nc", "report.html"}
    expected |= {f"figures/{stem}.{ext}" for stem in PAPER_FIGURES for ext in ("png", "svg")}
    assert names == expected
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stop_time_s"] == pytest.approx(1.05, abs=1e-12)
    assert summary["alpha_final_rad"] == pytest.approx(0.7378, abs=1e-12)
    ident = json.loads((out / "identification.json").read_text())
    assert ident["F1_N"] == pytest.approx(mp_identify(2900, 0.2, 0.7378, 1.05)[0], rel=1e-10)


@pytest.mark.parametrize("stem", PAPER_FIGURES)
def test_figure_files(paper_run, stem):
    _, _, out = paper_run
    png = out / "figures" / f"{stem}.png"
    width, height = png_size(png)
    assert png.stat().st_size > 20_000
    assert width >= 600 and 300 <= height <= 1200
    svg = ET.parse(out / "figures" / f"{stem}.svg").getroot()
    assert svg.tag.endswith("svg") and svg.get("width").endswith("pt")
    # the SVG and the PNG show the same figure size (150 dpi PNG, 72 pt per inch SVG)
    assert float(svg.get("width")[:-2]) / 72 == pytest.approx(width / 150, abs=0.02)


def test_fig15_points_lie_on_the_analytic_curve(paper_run):
    result, _, _ = paper_run
    rk, explicit = result.state_responses
    assert rk.method == "rk" and explicit.method == "explicit"
    data = rk.state_diagram()
    assert np.max(data["distance"]) < 1e-6
    away = data["alpha_dot_analytic"] > 0.05 * rk.alpha_dot0
    assert np.max(np.abs(data["alpha_dot"] - data["alpha_dot_analytic"])[away]) < 1e-6
    # the paper's Table 6 scheme at dt = 0.1 ms: first order, within 1e-5
    assert np.max(explicit.state_diagram()["distance"]) < 1e-5
    # the analytic curve under the states: Eq. 10 from alpha0 (where it starts at the release rate) to alpha_F
    assert data["curve_alpha"][0] == rk.alpha0 and data["curve_alpha"][-1] == rk.alpha_final
    assert data["curve_alpha_dot"][0] == pytest.approx(rk.alpha_dot0, rel=1e-9)


def test_identification_figure_data(paper_run):
    result, _, _ = paper_run
    ident = result.identification
    data = ident.line_curve()
    t = data["stop_time"]
    assert np.all(np.diff(t) < 0)  # t_F falls as F2/F2* rises
    assert t[0] == pytest.approx(ident.feasible_stop_times[1], rel=1e-13)
    assert t[-1] == pytest.approx(ident.feasible_stop_times[0], rel=1e-13)
    assert np.interp(ident.F2_ratio, data["F2_ratio"], t) == pytest.approx(1.05, abs=2e-4)


def test_report_contents(paper_run):
    result, _, out = paper_run
    text = (out / "report.html").read_text()
    F1, F2 = mp_identify(2900, 0.2, 0.7378, 1.05)
    assert f">{result.identification.F1:.5g}<" in text and f">{F1:.5g}<" in text
    assert f">{result.identification.F2:.5g}<" in text and f">{F2:.5g}<" in text
    from quality import report_number_faults  # one number format in every table: 5 significant digits at most

    assert text.count('<td class="num"') > 40 and report_number_faults(text) == []
    for stem in PAPER_FIGURES:
        assert f'<figure id="{stem}"><svg' in text, stem
    assert text.count("<svg") == len(PAPER_FIGURES)
    from quality import html_faults

    assert html_faults(text) == []
    lowered = text.lower()
    for fetch in ("<script", "<link", "<img", "@import", "url(http", 'src="http', "href=\"http"):
        assert fetch not in lowered, fetch


def test_report_escapes_user_text(tmp_path):
    body = (EXAMPLES / "paper.toml").read_text()
    body = body.replace('title = "Paper test: Table 7 (Oliveto et al.)"', 'title = "<script>alert(1)</script> & co"')
    (tmp_path / "c.toml").write_text(body)
    write_results(run_case(load_case(tmp_path / "c.toml")), tmp_path / "o", figures=False, data=False)
    text = (tmp_path / "o" / "report.html").read_text()
    assert "<script>" not in text
    assert "&lt;script&gt;alert(1)&lt;/script&gt; &amp; co" in text


def _chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        if shutil.which(name):
            return shutil.which(name)
    return None


@pytest.mark.slow
def test_report_renders_in_headless_chromium(paper_run, tmp_path):
    browser = _chromium()
    if browser is None:
        if os.environ.get("CI"):
            pytest.fail("chromium is not installed; .ci/run installs it")
        pytest.skip("chromium not installed (apt-get install chromium)")
    _, _, out = paper_run
    shot = tmp_path / "shot.png"
    cmd = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           f"--user-data-dir={tmp_path / 'profile'}", f"--screenshot={shot}", "--window-size=1200,3000",
           (out / "report.html").resolve().as_uri()]
    subprocess.run(cmd, capture_output=True, timeout=120, check=False)
    assert shot.exists(), "chromium wrote no screenshot"
    from matplotlib.image import imread

    img = imread(shot)[..., :3]
    assert img.shape[0] == 3000 and img.shape[1] == 1200
    dark = np.mean(img.mean(axis=2) < 0.5)  # text, lines, bars
    assert img.std() > 0.05 and dark > 0.005, (img.std(), dark)
    # the figures are drawn: the blue of the curves (#1f4e79) appears
    blue = np.all(np.abs(img - np.array([0x1F, 0x4E, 0x79]) / 255) < 0.08, axis=2)
    assert blue.sum() > 500
