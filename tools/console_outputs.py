"""Regenerate, or check, the console outputs the documentation shows.

Every ``console`` block of README.md and docs/ that shows a ``$ quickrelease ...`` command followed by its output is
run as written (a shell line: pipes included) from a folder laid out as the repository's root (``examples/`` and
nothing else), at 80 columns, stdout and stderr as a terminal shows them; the output replaces (``--write``) or is
compared with (``--check``) what the page shows, each line's trailing blanks aside. A line ``...`` of a shown output
stands for any lines (an excerpt: the lines around it must match in order), and numbers written with more than 12
significant digits are compared to 12 (their last digits depend on the platform's libm, not on the code).

    python tools/console_outputs.py --check              # every page; exit 1 and a diff where one is stale
    python tools/console_outputs.py --write docs/guide/uq.md

``tests/cli/test_console_outputs.py`` runs the check (the slow commands with ``QUICKRELEASE_SLOW=1``).
"""

from __future__ import annotations

import argparse
import difflib
import os
import re
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
COLUMNS = 80


@dataclass(frozen=True)
class Shown:
    """A command of a console block and the output the page shows under it."""

    page: Path
    line: int
    """1-based line of the ``$ `` command in the page."""
    command: str
    output: str
    span: tuple[int, int]
    """0-based [start, end) of the output's lines in the page."""

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def pages() -> list[Path]:
    return [ROOT / "README.md", *sorted(p for p in (ROOT / "docs").rglob("*.md") if "_build" not in p.parts)]


def shown_outputs(paths: list[Path] | None = None) -> list[Shown]:
    """Every ``$ quickrelease`` command of a console block with an output shown under it."""
    found = []
    for page in paths or pages():
        lines = page.read_text(encoding="utf-8").splitlines()
        i = 0
        while i < len(lines):
            if lines[i].strip() != "```console":
                i += 1
                continue
            j = i + 1
            while j < len(lines) and lines[j].strip() != "```":
                j += 1
            k = i + 1
            while k < j:
                if lines[k].startswith("$ quickrelease"):
                    end = k + 1
                    while end < j and not lines[end].startswith("$ "):
                        end += 1
                    if end > k + 1:
                        found.append(Shown(page, k + 1, lines[k][2:], normalise("\n".join(lines[k + 1:end])),
                                           (k + 1, end)))
                    k = end
                else:
                    k += 1
            i = j + 1
    return found


def normalise(text: str) -> str:
    """Trailing blanks of each line and trailing empty lines dropped."""
    return "\n".join(line.rstrip() for line in text.splitlines()).rstrip("\n")


_LONG_NUMBER = re.compile(r"-?\d+\.\d{9,}(?:e[-+]?\d+)?")


def _twelve_digits(text: str) -> str:
    return _LONG_NUMBER.sub(lambda m: format(float(m.group()), ".12g"), text)


def matches(shown: str, got: str) -> bool:
    """Whether ``got`` is what ``shown`` shows: line by line, a ``...`` line standing for any lines, long numbers
    to 12 significant digits."""
    pattern = "".join(r"(?:.*\n)*?" if line.strip() in ("...", "…") else re.escape(line) + r"\n"
                      for line in _twelve_digits(shown).splitlines())
    return re.fullmatch(pattern, _twelve_digits(got) + "\n") is not None


def run(command: str, folder: Path, timeout: float = 1800) -> str:
    """The command's output as a terminal shows it (stdout and stderr as they come), run by bash in ``folder``."""
    env = {**os.environ, "COLUMNS": str(COLUMNS), "PATH": f"{Path(sys.executable).parent}{os.pathsep}"
           f"{os.environ.get('PATH', '')}", "NO_COLOR": "1", "TERM": "dumb"}
    r = subprocess.run(["bash", "-c", command], cwd=folder, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       text=True, timeout=timeout)
    return normalise(r.stdout)


def root_like_folder() -> Path:
    """A new temporary folder laid out as the repository's root: ``examples/`` (copied) and nothing else."""
    folder = Path(tempfile.mkdtemp(prefix="quickrelease-console-"))
    shutil.copytree(ROOT / "examples", folder / "examples")
    return folder


def diff(shown: Shown, got: str) -> str:
    return "\n".join(difflib.unified_diff(shown.output.splitlines(), got.splitlines(), f"{shown.where} (shown)",
                                          f"{shown.where} (now)", lineterm=""))


def write(shown: Shown, got: str) -> None:
    """Replace the output under ``shown``'s command by ``got`` (the page re-read: earlier writes keep their place)."""
    lines = shown.page.read_text(encoding="utf-8").splitlines()
    start = shown.line  # the command's 0-based index + 1
    assert lines[start - 1][2:] == shown.command, shown.where
    end = start
    while end < len(lines) and not lines[end].startswith("$ ") and lines[end].strip() != "```":
        end += 1
    lines[start:end] = got.splitlines()
    shown.page.write_text("\n".join(lines) + "\n", encoding="utf-8")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--check", action="store_true", help="compare; exit 1 with a diff where an output is stale")
    mode.add_argument("--write", action="store_true", help="write the outputs of today's code into the pages")
    parser.add_argument("pages", nargs="*", type=Path, help="pages (default: README.md and every docs/ page)")
    args = parser.parse_args(argv)
    chosen = [p.resolve() for p in args.pages] or None
    stale = 0
    # bottom-up within a page, so that writing one output leaves the line numbers of those above it as they were
    for shown in sorted(shown_outputs(chosen), key=lambda s: (str(s.page), -s.line)):
        folder = root_like_folder()
        try:
            got = run(shown.command, folder)
        finally:
            shutil.rmtree(folder, ignore_errors=True)
        if matches(shown.output, got):
            print(f"ok      {shown.where}: {shown.command}")
            continue
        stale += 1
        if args.write:
            write(shown, got)
            print(f"written {shown.where}: {shown.command}")
        else:
            print(diff(shown, got))
    return 1 if stale and args.check else 0


if __name__ == "__main__":
    raise SystemExit(main())
