"""Sweeps reaching the ends of the floating-point range (issue 9, item 18): finite correct answers, or a flagged
case with its reason in the dataset and a count in the summary; never a silent NaN."""

import json
import math
from pathlib import Path

import numpy as np
import xarray as xr
from typer.testing import CliRunner

from quickrelease import batch
from quickrelease.cli import app

EXAMPLES = Path(__file__).parents[2] / "examples"


def test_negligible_friction_gives_the_frictionless_answer():
    # friction work below 2^-64 E_S changes nothing by a rounding unit: forces down to the smallest subnormal
    free = batch.release(2900.0, 0.2, 0.0, 0.0)
    for F in (5e-324, 1e-308, 1e-300):
        r = batch.release(2900.0, 0.2, F, F)
        assert int(r.status) == 0
        for key in ("stop_time", "alpha_final", "u_final", "peak_u_dot", "peak_v_ddot"):
            assert float(getattr(r, key)) == float(getattr(free, key)), key


def test_forces_beyond_the_range_are_flagged_not_silent():
    r = batch.release(2900.0, 0.2, np.array([400.0, 1e308, 400.0]), np.array([800.0, 800.0, 1e308]))
    assert r.status.tolist() == [0, 1, 1]
    assert np.all(np.isfinite(r.stop_time[:1])) and np.all(np.isnan(r.stop_time[1:]))
    assert "floating-point range" in batch.RELEASE_STATUS[1]
    s = batch.stop_time(2900.0, 0.2, 1e308, 800.0)
    assert math.isnan(float(s.stop_time))


def test_sweep_netcdf_flags_and_counts_them(tmp_path):
    out = tmp_path / "s.nc"
    r = CliRunner().invoke(app, ["sweep", str(EXAMPLES / "paper.toml"), "--grid", "F1=0,5e-324,1e-308,400,1e308 N",
                                 "--out", str(out), "--json"])
    assert r.exit_code == 0, r.output
    summary = json.loads(r.stdout)
    assert summary["flagged"] == 1
    ds = xr.open_dataset(out)
    assert ds.status.values.tolist() == [0, 0, 0, 0, 1]
    assert "floating-point range" in ds.status.attrs["long_name"]
    ok = ds.status.values == 0
    assert np.all(np.isfinite(ds.stop_time.values[ok])) and np.isnan(ds.stop_time.values[~ok]).all()
    assert ds.stop_time.values[1] == ds.stop_time.values[0] == ds.stop_time.values[2]
