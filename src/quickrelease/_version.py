"""The package's version, at the ground: modules that write it into their outputs import it from here, not
from the package's ``__init__`` (which imports them: a cycle)."""

from __future__ import annotations

__all__ = ["__version__"]


def _package_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("quickrelease")
    except PackageNotFoundError:  # running from a source tree
        return "0.0.0+unknown"


__version__ = _package_version()
del _package_version
