"""The package's version and the provenance attributes of NetCDF outputs, at the ground: modules that write
them into their outputs import them from here, not from the package's ``__init__`` or the run folder (which
import those modules: a cycle)."""

from __future__ import annotations

from typing import Any

__all__ = ["__version__", "provenance_attrs"]


def _package_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("quickrelease")
    except PackageNotFoundError:  # running from a source tree
        return "0.0.0+unknown"


__version__ = _package_version()
del _package_version


def provenance_attrs(prov: dict[str, Any]) -> dict[str, str]:
    """The provenance as NetCDF global attributes (text only): ``quickrelease_version``, ``input_file``,
    ``input_sha256`` (the text itself stays in the JSON files and the report)."""
    attrs = {"quickrelease_version": str(prov["quickrelease"])}
    if prov.get("input"):
        attrs["input_file"] = str(prov["input"]["name"])
        attrs["input_sha256"] = str(prov["input"]["sha256"])
    return attrs
