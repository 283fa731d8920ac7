"""Writing results to files: CSV, NetCDF and JSON, always atomically.

Every writer goes through :func:`atomic_path`: the data are written to a temporary
file in the destination folder, flushed to disk and renamed into place, so an
interrupted run never leaves a half-written file under the final name.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from .response import Response

__all__ = ["atomic_path", "write_json", "write_text", "write_csv", "read_csv", "write_netcdf", "read_netcdf",
           "COLUMN_UNITS"]

#: Time-history columns and their units (the CSV header carries the unit in the name).
COLUMN_UNITS: dict[str, str] = {
    "t_s": "s", "alpha_rad": "rad", "alpha_dot_rad_s": "rad/s", "alpha_ddot_rad_s2": "rad/s^2",
    "u_m": "m", "v_m": "m", "u_dot_m_s": "m/s", "v_dot_m_s": "m/s", "u_ddot_m_s2": "m/s^2",
    "v_ddot_m_s2": "m/s^2", "E_K_J": "J", "W_F_J": "J", "E_S_J": "J",
}


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success rename it to ``path``.

    On an exception the temporary file is removed and ``path`` is left as it was.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        with open(tmp_path, "rb+") as fh:
            os.fsync(fh.fileno())
        os.chmod(tmp_path, 0o666 & ~_umask())  # mkstemp makes 0600; give the file the usual mode
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


def write_json(data: dict[str, Any], path: str | Path) -> Path:
    """Write a JSON object atomically (no NaN: JSON has none)."""
    return write_text(json.dumps(data, indent=2, allow_nan=False) + "\n", path)


def write_csv(response: Response, path: str | Path) -> Path:
    """Write the time histories as CSV, one column per quantity, units in the names, full precision."""
    data = response.to_dict()
    names = list(data)
    matrix = np.column_stack([np.asarray(data[n], dtype=float) for n in names])
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(",".join(names) + "\n")
            np.savetxt(fh, matrix, delimiter=",", fmt="%.17g")
    return Path(path)


def read_csv(path: str | Path) -> dict[str, np.ndarray]:
    """Read a CSV written by :func:`write_csv` back into arrays (exactly)."""
    with open(path, encoding="utf-8") as fh:
        names = fh.readline().strip().split(",")
        matrix = np.loadtxt(fh, delimiter=",", ndmin=2)
    return {n: matrix[:, i] for i, n in enumerate(names)}


def write_netcdf(response: Response, path: str | Path, attrs: dict[str, Any] | None = None) -> Path:
    """Write the time histories as NetCDF (classic format, readable by xarray and every NetCDF tool).

    Variables are named as the CSV columns without the unit suffix, with a ``units`` attribute;
    the summary goes into global attributes.
    """
    from scipy.io import netcdf_file

    data = response.to_dict()
    n = response.t.size
    summary = {k: v for k, v in response.summary().items() if v is not None}
    summary.update(attrs or {})
    with atomic_path(path) as tmp:
        f = netcdf_file(tmp, "w", version=2)
        try:
            f.createDimension("time", n)
            for name, values in data.items():
                var_name = _var_name(name)
                var = f.createVariable(var_name, "d", ("time",))
                var[:] = np.asarray(values, dtype=float)
                var.units = COLUMN_UNITS[name]
            f.title = "quickrelease release time history"
            for key, value in summary.items():
                if isinstance(value, bool):
                    value = np.int32(value)
                elif isinstance(value, int):
                    value = np.int64(value) if abs(value) >= 2**31 else np.int32(value)
                elif isinstance(value, float):
                    value = np.float64(value)  # scipy would store a Python float as float32
                elif isinstance(value, str):
                    value = _text_attr(value)
                setattr(f, key, value)
        finally:
            f.close()
    return Path(path)


def _text_attr(text: str) -> bytes:
    """A text attribute as NetCDF classic stores text: UTF-8 bytes (NC_CHAR), the encoding the NetCDF
    conventions and xarray read back as text. scipy's writer encodes ``str`` as ASCII and fails on any
    other letter (a title "Prüfung", a test name in CJK)."""
    return text.encode("utf-8")


def _var_name(column: str) -> str:
    unit = COLUMN_UNITS[column]
    suffix = "_" + unit.replace("/", "_").replace("^", "")
    return column[: -len(suffix)] if column.endswith(suffix) else column


def read_netcdf(path: str | Path) -> dict[str, np.ndarray]:
    """Read the variables of a NetCDF file written by :func:`write_netcdf`."""
    from scipy.io import netcdf_file

    with netcdf_file(path, "r", mmap=False) as f:
        return {name: np.array(var[:]) for name, var in f.variables.items()}
