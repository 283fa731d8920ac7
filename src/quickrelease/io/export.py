"""Writing results to files: CSV, NetCDF and JSON, always atomically.

Every writer goes through :func:`atomic_path`: the data are written to a temporary
file in the destination folder, flushed to disk and renamed into place, so an
interrupted run never leaves a half-written file under the final name.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from ..device.response import TIME_HISTORIES, Response

__all__ = ["atomic_path", "write_json", "write_text", "write_csv", "read_csv", "write_netcdf", "read_netcdf",
           "COLUMN_UNITS"]

#: Time-history columns and their units (the CSV header carries the unit in the name).
COLUMN_UNITS: dict[str, str] = {column: unit for column, (_, unit, _) in TIME_HISTORIES.items()}


def jsonable(obj: Any) -> Any:
    """Plain JSON values, recursively: tuples and arrays as lists, numpy scalars as Python numbers, NaN and
    infinities as None (JSON has none: a standard error a record cannot give, a bound never reached)."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple | np.ndarray):
        return [jsonable(v) for v in list(obj)]
    if isinstance(obj, bool | np.bool_):
        return bool(obj)
    if isinstance(obj, int | np.integer):
        return int(obj)
    if isinstance(obj, float | np.floating):
        return float(obj) if math.isfinite(float(obj)) else None
    return obj


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success rename it to ``path``.

    On an exception the temporary file is removed and ``path`` is left as it was. Only a regular file is ever
    replaced: a device node, FIFO or folder at ``path`` raises :class:`~quickrelease.io.runfolder.OutputError`
    (a rename over it would remove it). The temporary name is hidden and, for a name near the file system's
    limit, shortened (:func:`~quickrelease.io.runfolder.staging_name`).
    """
    from .._files import file_kind, staging_name
    from ..errors import OutputError

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=staging_name(path.name, "", path.parent), suffix=".part",
                               dir=path.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        try:
            yield tmp_path
        except OSError as exc:  # name the file the user asked for (a writer's error may name none)
            if exc.filename is None:
                raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None
            raise
        with open(tmp_path, "rb+") as fh:
            os.fsync(fh.fileno())
        os.chmod(tmp_path, 0o666 & ~_umask())  # mkstemp makes 0600; give the file the usual mode
        try:
            mode = os.stat(path).st_mode
        except FileNotFoundError:
            mode = None
        if mode is not None and not stat.S_ISREG(mode):
            raise OutputError(f"{path}: is {file_kind(mode)}, not a regular file; it is never replaced")
        os.replace(tmp_path, path)
    except BaseException:
        tmp_path.unlink(missing_ok=True)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text(text: str, path: str | Path) -> Path:
    """Write text (UTF-8) atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_json(data: dict[str, Any], path: str | Path, provenance: dict[str, Any] | None = None) -> Path:
    """Write a JSON object atomically (no NaN: JSON has none); with ``provenance``
    (:func:`quickrelease.io.runfolder.provenance`) stated under the key ``provenance``."""
    if provenance is not None:
        data = {**data, "provenance": provenance}
    return write_text(json.dumps(data, indent=2, allow_nan=False) + "\n", path)


def write_csv(response: Response, path: str | Path) -> Path:
    """Write the time histories as CSV, one column per quantity, units in the names, full precision."""
    return write_columns(response.to_dict(), path)


def write_columns(columns: dict[str, Any], path: str | Path) -> Path:
    """Write equal-length number columns as CSV atomically: a header of the names (units in them), full
    precision, an empty cell for NaN (a sample a channel does not have)."""
    names = list(columns)
    matrix = np.column_stack([np.asarray(columns[n], dtype=float) for n in names])
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(",".join(names) + "\n")
            for row in matrix:
                fh.write(",".join("" if v != v else format(v, ".17g") for v in row) + "\n")
    return Path(path)


def write_dataset(ds: Any, path: str | Path, provenance: dict[str, Any] | None = None) -> Path:
    """Write an ``xarray.Dataset`` as NetCDF (classic format, as :func:`write_netcdf`) atomically, with the
    ``provenance`` (:func:`quickrelease.io.runfolder.provenance`) as global attributes."""
    if provenance is not None:
        from .._version import provenance_attrs

        ds = ds.assign_attrs(provenance_attrs(provenance))
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, engine="scipy", format="NETCDF3_64BIT")
    return Path(path)


def read_csv(path: str | Path) -> dict[str, np.ndarray]:
    """Read a CSV written by :func:`write_csv` back into arrays (exactly)."""
    with open(path, encoding="utf-8") as fh:
        names = fh.readline().strip().split(",")
        matrix = np.loadtxt(fh, delimiter=",", ndmin=2)
    return {n: matrix[:, i] for i, n in enumerate(names)}


def write_netcdf(response: Response, path: str | Path, attrs: dict[str, Any] | None = None,
                 provenance: dict[str, Any] | None = None) -> Path:
    """Write the time histories as NetCDF (classic format, readable by xarray and every NetCDF tool).

    The dataset of :meth:`Response.to_xarray`: variables named as the CSV columns without the unit suffix,
    on the time coordinate ``t``, with ``units`` and ``long_name``; the summary and ``attrs`` as global
    attributes, with the ``provenance`` (version, input file and its SHA-256). Text attributes are UTF-8 (a
    title "Prüfung" reads back letter for letter).
    """
    ds = response.to_xarray(provenance=provenance)
    for key, value in (attrs or {}).items():
        ds.attrs[key] = int(value) if isinstance(value, bool) else value
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, engine="scipy", format="NETCDF3_64BIT")
    return Path(path)


def read_netcdf(path: str | Path) -> dict[str, np.ndarray]:
    """The variables (and the time coordinate ``t``) of a NetCDF file written by :func:`write_netcdf`."""
    import xarray as xr

    with xr.open_dataset(path, engine="scipy") as ds:
        return {str(name): np.array(ds[name].values) for name in [*ds.coords, *ds.data_vars]}
