"""Parameter sweeps: the release envelope over a grid of inputs, as an xarray Dataset.

Any of the case's inputs may be swept (``force``, ``energy``, ``alpha0``, ``F1``, ``F2``, ``c``, ``m1``,
``m2``, ``L1``); the others keep the case's values (friction from ``[friction]``, or identified from
``[observations]``). Outputs per grid point: t_F, alpha_F, the stop reason, u_F, v_F, the initial
angular velocity, the peak head and hinge velocities, and E_S. All computed by :func:`batch.release`.

Backends: ``numpy`` computes the grid in memory; ``dask`` computes it in blocks along the first grid
dimension on a Dask cluster, writing each finished block into a Zarr store (xarray region writes, then
a marker file per block), so memory stays bounded by the block and ``resume`` skips finished blocks.

Outputs never lie (:mod:`quickrelease.io.runfolder`): a NetCDF file is written under a temporary name and
renamed when complete; a Zarr store is built in ``.NAME.partial`` beside ``out`` (its ``manifest.json``
holds the fingerprint of the case, the grids, the block size and the package version) and moved into
place only when every block is in, so a killed sweep leaves nothing at ``out`` that opens as a result.
``resume`` continues that unfinished store only when its fingerprint is this sweep's (else it refuses,
naming what differs) and computes only the blocks not marked done.
"""

from __future__ import annotations

import contextlib
import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from .. import batch
from .._threads import check_threads, refuse_with_dask, using_threads
from .._validate import check_size, check_workers
from ..device.statics import strain_energy_coefficient
from ..errors import ParameterError, QuickReleaseError
from ..io.case import Case
from ..report._style import STYLE, styled
from ..units import parse_quantity

__all__ = ["SWEEP_PARAMETERS", "OUTPUTS", "parse_grid", "sweep", "heatmap_figure"]

#: Sweepable inputs: quantity kind and unit.
SWEEP_PARAMETERS = {
    "force": ("force", "N"), "energy": ("energy", "J"), "alpha0": ("angle", "rad"), "F1": ("force", "N"),
    "F2": ("force", "N"), "c": ("dimensionless", "1"), "m1": ("mass", "kg"), "m2": ("mass", "kg"),
    "L1": ("length", "m"),
}
#: Long names of the sweepable inputs (the coordinates' ``long_name``).
SWEEP_LONG_NAMES = {
    "force": "push force P at release", "energy": "stored strain energy E_S", "alpha0": "release angle alpha0",
    "F1": "friction at the central hinges F1", "F2": "friction at the rail supports F2", "c": "mass factor c",
    "m1": "mass of a bar m1", "m2": "mass of the head m2", "L1": "length of a bar L1",
}
#: Outputs: (long name, unit).
OUTPUTS = {
    "stop_time": ("time from release to the end of the motion t_F", "s"),
    "alpha_final": ("final angle alpha_F", "rad"),
    "stopped_by": ("0: friction stop, 1: geometric limit (flat rhombus), 2: creeps towards it (stop_time inf)", "1"),
    "u_final": ("head stroke u_F", "m"),
    "v_final": ("central hinge opening v_F", "m"),
    "alpha_dot0": ("initial angular velocity (Eq. 6)", "rad/s"),
    "peak_u_dot": ("peak head velocity", "m/s"),
    "peak_v_dot": ("peak central hinge velocity", "m/s"),
    "peak_u_ddot": ("peak head acceleration", "m/s^2"),
    "peak_v_ddot": ("peak central hinge acceleration", "m/s^2"),
    "stored_energy": ("stored strain energy E_S", "J"),
    "status": ("0: computed, 1: outside the floating-point range (outputs NaN; batch.RELEASE_STATUS)", "1"),
}


def parse_grid(text: str) -> tuple[str, np.ndarray]:
    """``"force=500 kN:3000 kN:26"`` (start:stop:count, ends included) or ``"F1=100,200,400 N"``."""
    name, sep, spec = text.partition("=")
    name = name.strip()
    if not sep or name not in SWEEP_PARAMETERS:
        raise ParameterError("--grid", text, f"NAME=start:stop:count with NAME one of {', '.join(SWEEP_PARAMETERS)}")
    kind, _ = SWEEP_PARAMETERS[name]
    parts = [p.strip() for p in spec.split(":")]
    if len(parts) == 3:
        try:
            count = int(parts[2])
        except ValueError:
            raise ParameterError("--grid count", parts[2], "integers >= 1") from None
        if count < 1:
            raise ParameterError("--grid count", count, "integers >= 1")
        check_size(f"--grid {name} count", count, count, "grid values", bytes_each=8)
        lo = parse_quantity(parts[0], kind, name)
        hi = parse_quantity(parts[1], kind, name)
        with np.errstate(over="ignore", invalid="ignore"):
            values = np.linspace(lo, hi, count)
        if not np.all(np.isfinite(values)):  # the span hi - lo overflows
            raise ParameterError(f"--grid {name}", f"{lo:.6g}:{hi:.6g}", "spans whose length hi - lo is a finite "
                                 "float (below 1.798e+308)")
        return name, values
    items = [p.strip() for p in spec.split(",")]
    unit = items[-1].partition(" ")[2] if " " in items[-1] else ""
    values = [parse_quantity(f"{p} {unit}".strip() if " " not in p else p, kind, name) for p in items]
    if not values:
        raise ParameterError("--grid", text, "NAME=start:stop:count or NAME=v1,v2,... [unit]")
    return name, np.array(values)


def _base(case: Case) -> dict[str, float]:
    from .fit import case_friction

    d = case.device
    F1, F2, _ = case_friction(case)
    return {"force": case.push_force if case.push_force is not None else math.nan, "energy": case.stored_energy,
            "alpha0": case.alpha0, "F1": F1, "F2": F2, "c": case.mass_factor, "m1": d.m1, "m2": d.m2, "L1": d.L1}


def _validate(grids: dict[str, np.ndarray], case: Case) -> None:
    if not grids:
        raise ParameterError("--grid", "none", "at least one grid, e.g. --grid 'alpha0=0.1:0.5:41'")
    if "force" in grids and "energy" in grids:
        raise ParameterError("--grid", "force and energy", "one of the two (E_S follows from P by Eq. 2)")
    if "force" in grids and case.energy_given:
        raise ParameterError("--grid force", "with a given energy", "cases without [test] energy (E_S from Eq. 2)")
    checks = {"alpha0": (lambda v: (v > 0) & (v < 0.5 * np.pi), "(0, pi/2)"),
              "F1": (lambda v: v >= 0, "[0, inf)"), "F2": (lambda v: v >= 0, "[0, inf)")}
    for name, values in grids.items():
        test, valid = checks.get(name, (lambda v: v > 0, "(0, inf)"))
        bad = ~(np.isfinite(values) & test(values))
        if np.any(bad):
            raise ParameterError(name, float(values[bad][0]), valid, SWEEP_PARAMETERS[name][1])


def _compute(case: Case, grids: dict[str, np.ndarray], base: dict[str, float], block: slice | None = None,
             backend: str = "numpy"):
    """Outputs on the grid (or on rows ``block`` of its first dimension), shaped like the grid (computed by
    :func:`batch.release` on ``backend``: numpy or gpu)."""
    names = list(grids)
    axes = [grids[n] if (i or block is None) else grids[n][block] for i, n in enumerate(names)]
    mesh = np.meshgrid(*axes, indexing="ij", sparse=True)
    x = {name: base[name] for name in base}
    x.update(dict(zip(names, mesh, strict=True)))
    shape = tuple(a.size for a in axes)
    if "force" in grids or (case.push_force is not None and not case.energy_given and "alpha0" in grids):
        E_S = x["force"] ** 2 * strain_energy_coefficient(x["alpha0"], case.device)
    else:
        E_S = x["energy"]
    r = batch.release(E_S, x["alpha0"], x["F1"], x["F2"], x["c"], x["m1"], x["m2"], x["L1"], backend=backend)
    out = {k: np.broadcast_to(v, shape) for k, v in r.to_dict().items()}
    out["stored_energy"] = np.broadcast_to(E_S, shape)
    return out


_FLAGS = ("stopped_by", "status")


def _dataset(case: Case, grids: dict[str, np.ndarray], data: dict[str, np.ndarray] | None, base: dict[str, float]):
    import xarray as xr

    names = list(grids)
    coords = {n: (n, grids[n], {"units": SWEEP_PARAMETERS[n][1], "long_name": SWEEP_LONG_NAMES[n]}) for n in names}
    shape = tuple(grids[n].size for n in names)
    variables = {}
    for key, (long, unit) in OUTPUTS.items():
        values = data[key] if data is not None else np.zeros(shape, dtype=np.int8 if key in _FLAGS else float)
        variables[key] = (names, np.asarray(values, dtype=np.int8 if key in _FLAGS else float),
                          {"long_name": long, "units": unit})
    from ..io.runfolder import provenance, provenance_attrs

    attrs = {"title": f"quickrelease sweep: {case.title}", "case": case.source, "device": case.device.name,
             "Conventions": "CF-1.8", **provenance_attrs(provenance(case))}
    attrs.update({f"fixed_{k}": float(v) for k, v in base.items() if k not in grids and np.isfinite(v)})
    return xr.Dataset(variables, coords=coords, attrs=attrs)


def _check_optional(out: str | Path | None, backend: str) -> None:
    """The optional packages the output and the backend need, checked before any work
    (:func:`quickrelease.studies.distributed.check_optional`)."""
    from .distributed import check_optional

    check_optional(backend=backend, files=() if out is None else (out,))


def sweep(case: Case, grids: dict[str, np.ndarray], *, backend: str = "numpy", out: str | Path | None = None,
          scheduler: str | None = None, workers: int = 2, block_rows: int | None = None, resume: bool = False,
          overwrite: bool = False, log: Any = None, threads: int | None = None):
    """Release envelope over a grid of inputs; returns an xarray Dataset (dims: the grid names, in order).

    Parameters
    ----------
    case : Case
        Supplies the inputs not swept (and the device).
    grids : dict of str to array
        Swept inputs (see :data:`SWEEP_PARAMETERS`), SI units.
    backend : {"numpy", "dask", "gpu"}
        ``dask`` needs ``out`` ending in ``.zarr``; ``gpu`` computes the grid on a CUDA GPU (CuPy:
        ``pip install 'quickrelease[gpu]'``; within 1e-13 relative of the numpy backend's values).
    out : path, optional
        ``.nc`` (NetCDF) or ``.zarr`` (Zarr) file to write.
    block_rows : int, optional
        Rows of the first grid dimension per Dask block (default: about 10^6 points per block).
    resume : bool
        Dask backend: continue the unfinished store of ``out`` (same fingerprint only): keep its finished
        blocks and compute the rest.
    overwrite : bool
        Replace a Zarr store holding another sweep (or discard an unfinished one), or an existing NetCDF file
        (without it an existing file is refused: it may not be a sweep).
    log : callable, optional
        Receives one line per note (how many blocks a resume computes).
    threads : int, optional
        Threads of the compiled kernels, 1 to ``numba.config.NUMBA_NUM_THREADS`` (numpy backend only; default:
        numba's current count, all cores unless changed; :func:`quickrelease.using_threads`). The values are
        the same for any count. Refused with the Dask backend, whose tasks run on one thread each, and the gpu backend.
    """
    grids = {k: np.asarray(v, dtype=float) for k, v in grids.items()}
    _validate(grids, case)
    if backend not in ("numpy", "dask", "gpu"):
        raise ParameterError("backend", backend, "'numpy', 'dask' or 'gpu'")
    check_threads(threads)
    refuse_with_dask(threads, backend)
    if backend == "dask" and (out is None or not str(out).endswith(".zarr")):
        raise ParameterError("out", out, "a path ending in .zarr (the dask backend streams blocks into Zarr)")
    if out is not None and Path(out).suffix not in (".nc", ".zarr"):
        raise ParameterError("out", str(out), "a path ending in .nc (NetCDF) or .zarr (Zarr)")
    if resume and backend != "dask":
        raise ParameterError("resume", True, "the dask backend (a numpy sweep is written whole or not at all)")
    _check_optional(out, backend)
    check_workers("workers", workers)
    points = math.prod(g.size for g in grids.values())
    if backend != "dask":  # the whole grid is in memory (the dask backend streams blocks to disk)
        check_size("--grid", " x ".join(str(g.size) for g in grids.values()), points, "grid points")
    base = _base(case)
    rows_total = grids[next(iter(grids))].size
    if backend == "dask":
        per_row = int(np.prod([g.size for g in list(grids.values())[1:]]))
        if block_rows is not None and (isinstance(block_rows, bool) or not isinstance(block_rows, int | np.integer)
                                       or not 1 <= block_rows <= rows_total):
            raise ParameterError("--block-rows", block_rows, f"integers in [1, {rows_total}] (the values of the "
                                 f"first grid, {next(iter(grids))})")
        if block_rows is not None:
            check_size("--block-rows", block_rows, int(block_rows) * per_row, "grid points a block")
        block_rows = int(block_rows or max(1, 1_000_000 // max(per_row, 1)))
    folder = None
    if out is not None:  # pre-flight, before the work
        from ..io.runfolder import check_output_file

        if Path(out).suffix == ".zarr":
            folder = _store_folder(case, grids, out, block_rows if backend == "dask" else None, resume=resume,
                                   overwrite=overwrite)
        else:  # a NetCDF file: never over a device node, FIFO or folder; over a file only with overwrite
            check_output_file(out, "--file", overwrite)
    if backend != "dask":
        with using_threads(threads):
            data = _compute(case, grids, base, backend=backend)
        ds = _dataset(case, grids, data, base)
        if folder is not None:
            with folder.staged() as work:
                with _quiet_zarr():
                    ds.to_zarr(work, mode="w")  # the manifest is (re)written complete by the commit
        elif out is not None:
            _write_netcdf(ds, Path(out))
        return ds
    return _sweep_dask(case, grids, base, folder, scheduler, workers, block_rows, rows_total, log)


@contextlib.contextmanager
def _quiet_zarr():
    """Zarr 3's two-line warning that consolidated metadata (which xarray writes and reads, and which makes
    the store open fast) is not in the Zarr 3 specification, silenced where we write and open a store: it
    said nothing the user could act on, on every Zarr sweep. Other warnings pass."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r"Consolidated metadata is currently not part",
                                category=UserWarning)
        yield


def _store_folder(case: Case, grids: dict[str, np.ndarray], out, block_rows: int | None, *, resume: bool,
                  overwrite: bool):
    """The :class:`~quickrelease.io.runfolder.RunFolder` of a Zarr store: its fingerprint covers the case, the
    grids (names, order, values), the block size (dask) and the package version."""
    from ..io.runfolder import RunFolder, case_inputs

    inputs = {"case": case_inputs(case), "grids": {"names": list(grids), **{k: v for k, v in grids.items()}},
              "block_rows": block_rows}
    return RunFolder(out, "sweep", inputs, overwrite=overwrite, resume=resume, resumable=block_rows is not None)


def _write_netcdf(ds, path: Path) -> None:
    """Write the NetCDF file under a temporary name, renamed when complete."""
    from ..io.export import atomic_path
    from ..io.runfolder import output_error

    try:
        with atomic_path(path) as tmp:
            ds.to_netcdf(tmp, engine="scipy")
    except OSError as exc:
        raise output_error(exc, path) from None


def _block(case: Case, grids, base, path: str, rows: slice, index: int) -> int:
    """Compute rows of the first dimension and write them into the Zarr store; then mark the block done."""
    data = _compute(case, grids, base, rows)
    first = list(grids)[0]
    sub = {**grids, first: grids[first][rows]}
    ds = _dataset(case, sub, data, base).drop_vars(list(grids))
    ds.attrs = {}
    with _quiet_zarr():
        ds.to_zarr(path, region={first: rows}, mode="r+")
    Path(path, _DONE, f"{index:06d}").touch()
    return index


_DONE = "_quickrelease_done"
_TEMPLATE = "template"


def _sweep_dask(case, grids, base, folder, scheduler, workers, block_rows, rows_total, log):
    import xarray as xr

    from ..io.runfolder import output_error
    from .distributed import map_chunks

    blocks = [slice(i, min(i + block_rows, rows_total)) for i in range(0, rows_total, block_rows)]
    work = folder.open()
    try:
        done_dir = work / _DONE
        mark = done_dir / _TEMPLATE
        if not (mark.is_file() and mark.read_text(encoding="ascii", errors="replace") == folder.fingerprint):
            # a new store, or one killed before its template was whole: (re)build it; mode="w" empties it
            template = _dataset(case, grids, None, base)
            encoding = {v: {"chunks": (block_rows, *template[v].shape[1:])} for v in OUTPUTS}
            with _quiet_zarr():
                template.to_zarr(work, mode="w", compute=False, encoding=encoding)
            folder._write_manifest(False)
            done_dir.mkdir(parents=True, exist_ok=True)
            mark.write_text(folder.fingerprint, encoding="ascii")
        finished = {int(p.name) for p in done_dir.iterdir() if p.name.isdigit()}
        todo = [(case, grids, base, str(work), rows, i) for i, rows in enumerate(blocks) if i not in finished]
        if log is not None and len(todo) < len(blocks):
            log(f"resuming {folder.given}: {len(blocks) - len(todo)} of {len(blocks)} blocks finished, "
                f"computing {len(todo)}")
        for _ in map_chunks(_block, todo, scheduler, workers):
            pass
        if {int(p.name) for p in done_dir.iterdir() if p.name.isdigit()} != set(range(len(blocks))):
            raise QuickReleaseError(f"{folder.given}: blocks are missing after the sweep; run it again with --resume")
    except OSError as exc:  # a full disk: nothing is left (a resumed run's earlier blocks stay)
        folder.abandon(force=True)
        raise output_error(exc, folder.given) from None
    folder.commit()
    with _quiet_zarr():
        return xr.open_zarr(folder.out)


def _even(v: np.ndarray) -> bool:
    """Evenly spaced (to 1e-9 of the step) with at least two values."""
    if v.size < 2:
        return False
    step = np.diff(v)
    return bool(step[0] != 0 and np.all(np.abs(step - step[0]) <= 1e-9 * abs(step[0])))


_TITLES = {"stop_time": "stop time $t_F$", "alpha_final": r"final angle $\alpha_F$", "u_final": "head stroke $u_F$",
           "v_final": "hinge opening $v_F$", "peak_u_dot": "peak head velocity", "peak_v_dot": "peak hinge velocity"}


@styled
def heatmap_figure(ds, fig=None, ax=None) -> Any:
    """Heat maps of t_F, alpha_F, u_F, v_F and the peak velocities over the first two grid dimensions
    (other dimensions at their first value); line plots for a one-dimensional sweep. ``ax``: six Axes to draw
    into (2 x 3, in reading order). Returns the figure."""
    from ..report._style import panels

    names = list(ds.dims)
    keys = ["stop_time", "alpha_final", "u_final", "v_final", "peak_u_dot", "peak_v_dot"]
    fig, axes = panels(9.0, 5.6, (2, 3), fig=fig, ax=ax, left=0.08, right=0.97, bottom=0.1, top=0.9, wspace=0.45,
                       hspace=0.45)
    sel = {n: 0 for n in names[2:]}
    for panel, key in zip(axes.flat, keys, strict=True):
        da = ds[key].isel(sel) if sel else ds[key]
        long, unit = OUTPUTS[key]
        if len(names) == 1:
            panel.plot(ds[names[0]].values, da.values, color="#1f4e79")
            panel.set_xlabel(f"{names[0]} [{SWEEP_PARAMETERS[names[0]][1]}]")
            panel.set_ylabel(f"[{unit}]")
        else:
            x, y = ds[names[1]].values, ds[names[0]].values
            z = np.asarray(da.values, dtype=float)
            if _even(x) and _even(y):  # one image per panel: seconds and a small SVG even for 1000 x 1000
                dx, dy = (x[-1] - x[0]) / (x.size - 1), (y[-1] - y[0]) / (y.size - 1)
                mesh = panel.imshow(z, origin="lower", aspect="auto", cmap="viridis",
                                 extent=(x[0] - dx / 2, x[-1] + dx / 2, y[0] - dy / 2, y[-1] + dy / 2))
            else:  # rasterised: an SVG holds one image per panel, not a path per cell
                mesh = panel.pcolormesh(x, y, z, shading="auto", cmap="viridis", rasterized=True)
            fig.colorbar(mesh, ax=panel, label=f"[{unit}]")
            limit = np.asarray(ds["stopped_by"].isel(sel).values if sel else ds["stopped_by"].values) == 1
            if limit.any() and not limit.all():
                panel.contour(x, y, limit, levels=[0.5], colors="w", linewidths=0.8).set_rasterized(True)
            panel.set_xlabel(f"{names[1]} [{SWEEP_PARAMETERS[names[1]][1]}]")
            panel.set_ylabel(f"{names[0]} [{SWEEP_PARAMETERS[names[0]][1]}]")
        panel.set_title(_TITLES[key], fontsize=STYLE["legend.fontsize"])
    extra = f" ({', '.join(f'{n} = {float(ds[n][0]):.4g}' for n in names[2:])})" if names[2:] else ""
    if ax is None:
        fig.suptitle(f"Release envelope over the sweep{extra}; white line: the geometric limit")
    return fig
