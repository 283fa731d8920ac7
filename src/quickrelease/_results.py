"""The result protocol, at the ground: what a result type offers people, without importing the tables.

A result type (``Response``, ``Identification``, ``FitResult``, ...) has a ``summary()`` (a dictionary keyed the
way JSON needs it) and mixes in :class:`Summarised` for a short ``repr`` and a notebook table
(``_repr_html_``). The formatting itself belongs to the presentation layer (:mod:`quickrelease.report.display`),
which registers its two functions here when it is imported (``import quickrelease`` does it); the physics and the
studies import this module only, never the tables' module.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["Summarised", "register_formatters"]

#: The presentation layer's formatters: ``repr(name, summary, keys)`` and ``html(name, summary)``.
_FORMATTERS: dict[str, Callable[..., str]] = {}


def register_formatters(short_repr: Callable[[str, Mapping[str, Any], tuple[str, ...]], str],
                        summary_html: Callable[[str, Mapping[str, Any]], str]) -> None:
    """Install the functions that format a result's ``repr`` and its notebook table (called by
    :mod:`quickrelease.report.display` when it is imported)."""
    _FORMATTERS["repr"] = short_repr
    _FORMATTERS["html"] = summary_html


class Summarised:
    """Mixin of the result types: a short ``repr`` and a notebook table (``_repr_html_``), both from the
    type's ``summary()``. Dataclasses using it are declared with ``repr=False`` so this repr is kept."""

    #: Summary keys the repr shows (default: the first five scalar entries).
    _repr_keys: tuple[str, ...] = ()

    def __repr__(self) -> str:
        fmt = _FORMATTERS.get("repr")
        if fmt is None:  # the presentation layer not imported (never after ``import quickrelease``)
            return f"{type(self).__name__}(...)"
        return fmt(type(self).__name__, self.summary(), self._repr_keys)  # type: ignore[attr-defined]

    def _repr_html_(self) -> str:
        return _FORMATTERS["html"](type(self).__name__, self.summary())  # type: ignore[attr-defined]
