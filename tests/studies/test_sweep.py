"""Sweeps: grid parsing, values against the single-release solver, Dask blocks and resume."""

import importlib.util
import shutil
from pathlib import Path

import numpy as np
import pytest

from quickrelease import ParameterError, simulate, strain_energy
from quickrelease.io.case import load_case
from quickrelease.studies.sweep import heatmap_figure, parse_grid, sweep

EXAMPLES = Path(__file__).parents[2] / "examples"
HAS_DASK = importlib.util.find_spec("dask") is not None and importlib.util.find_spec("zarr") is not None


def test_parse_grid():
    name, v = parse_grid("force=500 kN:3000 kN:26")
    assert name == "force" and v.size == 26 and v[0] == 500e3 and v[-1] == 3000e3
    assert parse_grid("alpha0=0.1:0.5:41")[1][20] == pytest.approx(0.3)
    assert parse_grid("F1=100,200,400 N")[1].tolist() == [100.0, 200.0, 400.0]
    assert parse_grid("alpha0=5 deg:10 deg:2")[1][1] == pytest.approx(np.radians(10))


@pytest.mark.parametrize("text,match", [("P=1:2:3", "NAME=start:stop:count"), ("force=1 m:2 m:3", "expected a force"),
                                        ("alpha0=0.1:0.5:0", "count = 0")])
def test_bad_grids(text, match):
    with pytest.raises(ValueError, match=match):
        parse_grid(text)


def test_values_match_single_releases():
    case = load_case(EXAMPLES / "larger_push.toml")
    grids = {"force": np.array([1000e3, 2200e3]), "alpha0": np.array([0.2, 0.3])}
    ds = sweep(case, grids)
    assert ds.stop_time.dims == ("force", "alpha0") and ds.stop_time.attrs["units"] == "s"
    assert ds.force.attrs == {"units": "N", "long_name": "push force P at release"}  # labelled axes in .plot()
    assert all("long_name" in ds[v].attrs and "units" in ds[v].attrs for v in ds.data_vars)
    for i, P in enumerate(grids["force"]):
        for j, a0 in enumerate(grids["alpha0"]):
            E = strain_energy(P, a0, case.device).total
            r = simulate(E, a0, case.F1, case.F2, device=case.device)
            assert float(ds.stored_energy[i, j]) == pytest.approx(E, rel=1e-13)
            assert float(ds.stop_time[i, j]) == pytest.approx(r.stop_time, rel=1e-12)
            assert float(ds.u_final[i, j]) == pytest.approx(r.u_final, rel=1e-12)
            assert int(ds.stopped_by[i, j]) == (r.stopped_by == "geometric_limit")


def test_identified_friction_is_used_without_friction_table(tmp_path):
    ds = sweep(load_case(EXAMPLES / "paper.toml"), {"alpha0": np.array([0.2])})
    # the paper case with its identified friction stops at the observed alpha_F and t_F
    assert float(ds.alpha_final[0]) == pytest.approx(0.7378, abs=1e-12)
    assert float(ds.stop_time[0]) == pytest.approx(1.05, abs=1e-12)


def test_bad_sweeps():
    case = load_case(EXAMPLES / "larger_push.toml")
    with pytest.raises(ParameterError, match="alpha0 = 2 rad is outside"):
        sweep(case, {"alpha0": np.array([0.2, 2.0])})
    with pytest.raises(ParameterError, match="force and energy"):
        sweep(case, {"force": np.array([1e6]), "energy": np.array([1e3])})
    with pytest.raises(ParameterError, match="ending in .zarr"):
        sweep(case, {"F1": np.array([100.0])}, backend="dask", out="x.nc")


def test_netcdf_output_and_heatmaps(tmp_path):
    import xarray as xr

    case = load_case(EXAMPLES / "larger_push.toml")
    ds = sweep(case, {"force": np.linspace(5e5, 3e6, 6), "alpha0": np.linspace(0.1, 0.5, 5)}, out=tmp_path / "s.nc")
    back = xr.open_dataset(tmp_path / "s.nc")
    np.testing.assert_array_equal(back.stop_time.values, ds.stop_time.values)
    assert 0 < float(ds.stopped_by.mean()) < 1  # the grid crosses the geometric limit
    fig = heatmap_figure(ds)
    assert len(fig.axes) == 12  # six panels and their colour bars
    import hashlib

    from quality import figure_faults

    assert figure_faults(fig) == []
    assert back.attrs["input_sha256"] == hashlib.sha256((EXAMPLES / "larger_push.toml").read_bytes()).hexdigest()


def _mtimes(store, block_rows, blocks):
    """mtime_ns of every chunk file of the given blocks (zarr v3 layout: VAR/c/ROWBLOCK/...), by path."""
    out = {}
    for var in ("stop_time", "u_final", "alpha_final"):  # never the fill value (zarr skips such chunks)
        for b in blocks:
            for f in (store / var / "c" / str(b)).rglob("*"):
                if f.is_file():
                    out[str(f.relative_to(store))] = f.stat().st_mtime_ns
    return out


@pytest.mark.slow
@pytest.mark.skipif(not HAS_DASK, reason="dask/zarr not installed")
def test_dask_blocks_resume_and_match_numpy(tmp_path):
    import json

    import xarray as xr

    case = load_case(EXAMPLES / "larger_push.toml")
    grids = {"force": np.linspace(5e5, 3e6, 12), "alpha0": np.linspace(0.1, 0.5, 7)}
    ref = sweep(case, grids)
    path = tmp_path / "s.zarr"
    sweep(case, grids, backend="dask", out=path, block_rows=3, workers=1)
    np.testing.assert_array_equal(xr.open_zarr(path).stop_time.values, ref.stop_time.values)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.zarr"]  # no staging folder left
    # the state a kill leaves: an unfinished store beside --out, blocks 1 and 2 not done (one half-written)
    staging = tmp_path / ".s.zarr.partial"
    shutil.copytree(path, staging)
    shutil.rmtree(path)
    manifest = json.loads((staging / "manifest.json").read_text())
    (staging / "manifest.json").write_text(json.dumps({**manifest, "complete": False}))
    for b in (1, 2):
        (staging / "_quickrelease_done" / f"{b:06d}").unlink()
    shutil.rmtree(staging / "stop_time" / "c" / "1")
    with pytest.raises(Exception, match="pass --resume"):
        sweep(case, grids, backend="dask", out=path, block_rows=3)
    # a resume with a changed grid (issue 9 item 1: 500 -> 250 rows returned 500 rows), block size or case
    changed = [({"force": grids["force"][:6], "alpha0": grids["alpha0"]}, case, 3, "force"),
               ({"force": grids["force"], "alpha0": np.linspace(0.1, 0.6, 7)}, case, 3, "alpha0"),
               (grids, case, 4, "block_rows"),
               (grids, case.replace(mass_model=1.0), 3, "case")]
    for g, c, rows, name in changed:
        with pytest.raises(Exception, match=f"cannot resume.*{name}"):
            sweep(c, g, backend="dask", out=path, block_rows=rows, resume=True)
    kept = _mtimes(staging, 3, (0, 3))
    assert len(kept) == 6  # three variables, blocks 0 and 3
    notes = []
    ds = sweep(case, grids, backend="dask", out=path, block_rows=3, resume=True, workers=1, log=notes.append)
    assert notes == [f"resuming {path}: 2 of 4 blocks finished, computing 2"]
    assert _mtimes(path, 3, (0, 3)) == kept  # the finished blocks were not written again
    for key in ref.data_vars:
        np.testing.assert_array_equal(ds[key].values, ref[key].values)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.zarr"]


@pytest.mark.skipif(not HAS_DASK, reason="dask/zarr not installed")
def test_numpy_zarr_store_is_staged_and_fingerprinted(tmp_path):
    import xarray as xr

    case = load_case(EXAMPLES / "larger_push.toml")
    grids = {"F1": np.linspace(100.0, 900.0, 5), "F2": np.linspace(500.0, 900.0, 3)}
    path = tmp_path / "s.zarr"
    ref = sweep(case, grids, out=path)
    np.testing.assert_array_equal(xr.open_zarr(path).u_final.values, ref.u_final.values)
    smaller = {"F1": grids["F1"][:3], "F2": grids["F2"]}
    with pytest.raises(Exception, match="another run.*--overwrite"):
        sweep(case, smaller, out=path)
    with pytest.raises(ParameterError, match="resume"):
        sweep(case, smaller, out=path, resume=True)
    sweep(case, smaller, out=path, overwrite=True)
    assert xr.open_zarr(path).sizes["F1"] == 3
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.zarr"]


@pytest.mark.parametrize("spacing", ["even", "uneven"])
def test_heatmaps_of_a_large_grid_are_small(spacing):
    """Issue 9 item 7: a 1000 x 1000 sweep wrote a 1.14 GB SVG (one path per cell); panels are images now.
    The vector SVG of this 400 x 400 grid is about 180 MB; the rasterised one about 0.4 MB."""
    import io

    import xarray as xr

    from quickrelease.studies.sweep import OUTPUTS

    n = 400 if spacing == "even" else 300
    f = np.linspace(5e5, 3e6, n) if spacing == "even" else np.geomspace(5e5, 3e6, n)
    a = np.linspace(0.1, 0.5, n)
    F, A = np.meshgrid(f, a, indexing="ij")
    data = {k: (("force", "alpha0"), np.sin(F / 3e5) * A) for k in OUTPUTS}
    data["stopped_by"] = (("force", "alpha0"), (F * A > 6e5).astype(np.int8))
    fig = heatmap_figure(xr.Dataset(data, coords={"force": f, "alpha0": a}))
    buf = io.BytesIO()
    fig.savefig(buf, format="svg", dpi=150)
    assert buf.tell() < 2_000_000, buf.tell()
    assert buf.getvalue().count(b"<image") >= 6  # one raster per panel
