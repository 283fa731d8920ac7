"""Checks of what a reader sees, on objects, not pixels: an HTML page's validity and a figure's labels.

``html_faults(text)``: well-formed (every non-void element closed, in order), no duplicate ``id``, every local
link (``href="#x"``, ``xlink:href="#x"``, ``url(#x)``) resolves to an ``id`` of the page.
``table_faults(text)``: a command's table output without JSON keys, long numbers, ``None`` or raw exponents.
``report_number_faults(page)``: the same for the numeric cells of a report's tables.
``figure_faults(fig)``: every axis that shows tick labels has a label with a unit in brackets, units written
one way (``m/s²``, never ``m/s^2`` or ``m s-2``), every labelled artist in a legend, every text at one of the
package style's font sizes.
"""

from __future__ import annotations

import re
from collections import Counter
from html.parser import HTMLParser

from quickrelease.report._style import FONT_SIZES

VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta", "source", "track", "wbr"}


class _Checker(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.stack: list[tuple[str, tuple[int, int]]] = []
        self.ids: list[str] = []
        self.refs: list[str] = []
        self.faults: list[str] = []
        self.doctype = False

    def handle_decl(self, decl: str) -> None:
        self.doctype = self.doctype or decl.lower() == "doctype html"

    def _attrs(self, attrs) -> None:
        for name, value in attrs:
            if value is None:
                continue
            if name == "id":
                self.ids.append(value)
            if name in ("href", "xlink:href") and value.startswith("#"):
                self.refs.append(value[1:])
            self.refs += re.findall(r"url\(#([^)]+)\)", value)

    def handle_starttag(self, tag, attrs) -> None:
        self._attrs(attrs)
        if tag not in VOID:
            self.stack.append((tag, self.getpos()))

    def handle_startendtag(self, tag, attrs) -> None:  # <path ... /> in inline SVG
        self._attrs(attrs)

    def handle_endtag(self, tag) -> None:
        if tag in VOID:
            return
        if not self.stack:
            self.faults.append(f"</{tag}> at {self.getpos()} closes nothing")
            return
        open_tag, pos = self.stack.pop()
        if open_tag != tag:
            self.faults.append(f"</{tag}> at {self.getpos()} closes <{open_tag}> opened at {pos}")

    def handle_data(self, data) -> None:
        if self.stack and self.stack[-1][0] == "style":
            self.refs += re.findall(r"url\(#([^)]+)\)", data)


def html_faults(text: str) -> list[str]:
    """What is wrong with an HTML page (an empty list when nothing is)."""
    checker = _Checker()
    checker.feed(text)
    checker.close()
    faults = list(checker.faults)
    if not checker.doctype:
        faults.append("no <!DOCTYPE html>")
    faults += [f"<{tag}> opened at {pos} is never closed" for tag, pos in checker.stack]
    dups = [i for i, n in Counter(checker.ids).items() if n > 1]
    if dups:
        faults.append(f"{len(dups)} duplicate ids, e.g. {dups[:3]}")
    known = set(checker.ids)
    missing = sorted({r for r in checker.refs if r not in known})
    if missing:
        faults.append(f"{len(missing)} local links to no id, e.g. {missing[:3]}")
    return faults


UNIT = re.compile(r"\[[^\[\]]+\]")
PLAIN_POWERS = re.compile(r"\^\d|\^-|\bs-\d|\bm s\b")


def _number(text: str) -> bool:
    try:
        float(text.replace("\u2212", "-").replace("$", "").replace("\\mathdefault{", "").replace("}", ""))
    except ValueError:
        return False
    return True


def _shows_ticks(axis) -> bool:
    """The axis shows numbers (categories, e.g. the names of the terms of a bar chart, need no unit)."""
    return any(t.get_visible() and _number(t.get_text().strip()) for t in axis.get_ticklabels())


def figure_faults(fig) -> list[str]:
    """What a reader of ``fig`` would miss (an empty list when nothing): see the module's docstring."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    if not isinstance(fig.canvas, FigureCanvasAgg):
        FigureCanvasAgg(fig)
    fig.canvas.draw()  # tick labels exist only once drawn
    faults = []
    legend_texts = set()
    legends = [ax.get_legend() for ax in fig.axes] + list(fig.legends)
    for legend in legends:
        if legend is not None:
            legend_texts |= {t.get_text() for t in legend.get_texts()}
    for k, ax in enumerate(fig.axes):
        where = f"axes {k} ({ax.get_title()[:40]!r})"
        if not ax.axison:  # a panel of text
            continue
        for name, axis, label in (("x", ax.xaxis, ax.get_xlabel()), ("y", ax.yaxis, ax.get_ylabel())):
            if _shows_ticks(axis) and not UNIT.search(label):
                faults.append(f"{where}: {name} label {label!r} has no [unit]")
        artists = [*ax.lines, *ax.collections, *ax.patches, *ax.containers, *ax.images]
        for artist in artists:
            label = str(artist.get_label())
            if label and not label.startswith("_") and label not in legend_texts:
                faults.append(f"{where}: {label!r} is in no legend")
    for text in fig.findobj(lambda a: hasattr(a, "get_text") and hasattr(a, "get_fontsize")):
        content = text.get_text()
        if not content.strip() or not text.get_visible():
            continue
        if PLAIN_POWERS.search(re.sub(r"\$[^$]*\$", "", content)):  # mathtext ($^2$) is drawn raised
            faults.append(f"unit not written as superscript: {content!r}")
        if text.get_fontsize() not in FONT_SIZES:
            faults.append(f"font size {text.get_fontsize()} (not one of {sorted(FONT_SIZES)}): {content[:40]!r}")
    return faults


#: A JSON key with its unit suffix (``push_force_N``, ``stop_time_s``, ``peak_v_dot_m_s``) shown to a person.
JSON_KEY = re.compile(r"\b[A-Za-z]\w*?_(?:N|s|m|J|rad|kg|Hz|Pa|deg|m_s|m_s2|rad_s|rad_s2|N_m)\b")
#: A number as printed: sign, digits (with thousands separators), decimals, exponent.
NUMBER = re.compile(r"(?<![\w.])[-+]?(\d[\d,]*(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?(?![\w.])")
#: Python's raw float exponent (``1.6e+04``, ``2.5e-08``): a number nobody formatted.
RAW_EXPONENT = re.compile(r"\d[eE][-+]0\d|\d[eE]\+\d")
#: The paper's and the building's symbols that look like keys: slider friction, superstructure period, damping.
SYMBOLS = {"F_s", "T_s", "zeta_s"}
PLUS_MINUS = re.compile(r"[-+]?[\d.]+(?:[eE][-+]?\d+)? ±")
QUOTED = re.compile(r"'[^'\n]*'|\"[^\"\n]*\"")


def _significant(mantissa: str) -> int:
    digits = mantissa.replace(",", "")
    whole = "." not in digits
    digits = digits.replace(".", "").lstrip("0")
    return len(digits.rstrip("0") if whole else digits)


def table_faults(text: str, digits: int = 8) -> list[str]:
    """What a person should not meet in a command's table output (not its ``--json``): JSON keys with unit
    suffixes (``push_force_N``), numbers with more than ``digits`` significant digits, Python's ``None``, raw
    float exponents (``1.6e+04``). Quoted text (file and column names, the TOML a command suggests) is
    left alone."""
    faults = []
    for n, line in enumerate(text.splitlines(), 1):
        bare = QUOTED.sub("''", line)
        for key in set(JSON_KEY.findall(bare)) - SYMBOLS:
            faults.append(f"line {n}: JSON key {key!r}: {line.strip()}")
        if re.search(r"\bNone\b", bare):
            faults.append(f"line {n}: None: {line.strip()}")
        if RAW_EXPONENT.search(bare):
            faults.append(f"line {n}: raw exponent: {line.strip()}")
        for match in NUMBER.finditer(PLUS_MINUS.sub("±", bare)):  # a value before ± has the digits of its error
            if _significant(match.group(1)) > digits:
                faults.append(f"line {n}: {match.group(0)} has more than {digits} significant digits")
    return faults


def report_number_faults(page: str, digits: int = 8) -> list[str]:
    """:func:`table_faults` over the numeric cells (``<td class="num">``) of an HTML report: one number format
    in every table (8 significant digits at most, as the command line's tables: an estimate shows the digits
    its uncertainty supports, 2.000080 s for an interval half-width of 5.7e-5 s; no raw exponents, no None)."""
    cells = re.findall(r'<td class="num"[^>]*>(.*?)</td>', page, re.S)
    if not cells:
        return ["no numeric cells"]
    return table_faults("\n".join(cells), digits=digits)


def overlap_faults(fig, samples: int = 40) -> list[str]:
    """Legends that cover something a reader needs (an empty list when none): a legend's box, once drawn,
    overlapping another text of its axes (a value beside a bar, a note) or holding a point of a curve of its
    axes (each line's segments sampled ``samples`` times in display coordinates; markers-only lines at their
    points). Horizontal/vertical reference lines count like curves."""
    import numpy as np
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    if not isinstance(fig.canvas, FigureCanvasAgg):
        FigureCanvasAgg(fig)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    faults = []
    for k, ax in enumerate(fig.axes):
        legend = ax.get_legend()
        if legend is None or not legend.get_visible():
            continue
        box = legend.get_window_extent(renderer)
        where = f"axes {k} ({ax.get_title()[:40]!r})"
        for text in ax.texts:
            if text.get_text().strip() and text.get_window_extent(renderer).overlaps(box):
                faults.append(f"{where}: legend covers the text {text.get_text()[:40]!r}")
        for line in ax.lines:
            xy = line.get_transform().transform(np.asarray(line.get_xydata(), dtype=float))
            xy = xy[np.all(np.isfinite(xy), axis=1)]
            if line.get_linestyle() not in ("None", "", " ") and len(xy) > 1:
                s = np.linspace(0.0, 1.0, samples, endpoint=False)
                xy = np.concatenate([a + s[:, None] * (b - a) for a, b in zip(xy[:-1], xy[1:], strict=True)] + [xy[-1:]])
            inside = (xy[:, 0] > box.x0) & (xy[:, 0] < box.x1) & (xy[:, 1] > box.y0) & (xy[:, 1] < box.y1)
            if np.any(inside):
                faults.append(f"{where}: legend covers {int(inside.sum())} point(s) of {line.get_label()!r}")
    return faults
