"""The documentation site: its examples run, its command lines name real options, its internal links resolve.

The site itself is built by ``sphinx-build -W -b html docs docs/_build/html`` (``.ci/run`` does it after
the tests, then runs ``test_every_internal_link_of_the_built_site_resolves`` on that build).
"""

import os
import re
import shlex
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest
import typer

from quickrelease.cli import app

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
PAGES = sorted(p for p in DOCS.rglob("*.md") if "_build" not in p.parts)
BLOCKS = [(page, i, code) for page in PAGES
          for i, code in enumerate(re.findall(r"^```python\n(.*?)^```", page.read_text(encoding="utf-8"), re.S | re.M))]


def test_the_docs_have_python_examples():
    assert len(BLOCKS) >= 2


@pytest.mark.parametrize("page, index, code", BLOCKS, ids=[f"{p.relative_to(DOCS)}-{i + 1}" for p, i, _ in BLOCKS])
def test_docs_python_block_runs(page, index, code, tmp_path, monkeypatch):
    (tmp_path / "examples").symlink_to(ROOT / "examples")  # the examples' relative paths, outputs in tmp
    monkeypatch.chdir(tmp_path)
    exec(compile(code, f"{page.relative_to(ROOT)} python block {index + 1}", "exec"), {"__name__": "__docs__"})  # noqa: S102


# --- command lines of the docs and the README: every command and option they show exists ----------------------

def _command_lines():
    lines = []
    for page in [*PAGES, ROOT / "README.md"]:
        text = page.read_text(encoding="utf-8")
        for line in re.findall(r"^\$ (quickrelease .*)$", text, re.M):
            lines.append((page.name, line))
        for line in re.findall(r"`(quickrelease [a-z]+ [^`]*)`", text):
            lines.append((page.name, line))
    return lines


COMMAND_LINES = _command_lines()


def unknown_options(line: str) -> list[str]:
    """The command and options of ``line`` that the Typer app does not have (empty: all exist)."""
    group = typer.main.get_command(app)
    words = shlex.split(line.split(" | ")[0].split(" > ")[0].split("#")[0])[1:]
    if not words or words[0].startswith("-"):
        return [w for w in words if w.startswith("-") and w.split("=")[0] not in {"--version", "-h", "--help"}]
    command = group.commands.get(words[0])
    if command is None:
        return [words[0]]
    known = {name for param in command.params for name in (*param.opts, *param.secondary_opts)}
    return [w for w in words[1:] if w.startswith("-") and w.split("=")[0] not in known | {"--help", "-h"}]


def test_the_docs_show_command_lines():
    assert len(COMMAND_LINES) >= 20


@pytest.mark.parametrize("page, line", COMMAND_LINES)
def test_docs_command_lines_name_real_options(page, line):
    assert unknown_options(line) == [], f"{page}: {line}"


def test_the_option_check_catches_a_wrong_option():
    assert unknown_options("quickrelease simulate --force 1 --alpha0 0.2 --f3 1") == ["--f3"]
    assert unknown_options("quickrelease simulat --force 1") == ["simulat"]


# --- internal links of a built site ------------------------------------------------------------------------------

class _Page(HTMLParser):
    def __init__(self):
        super().__init__()
        self.ids: set[str] = set()
        self.links: list[str] = []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        for key in ("id", "name") if tag != "meta" else ():
            if attrs.get(key):
                self.ids.add(attrs[key])
        for key in ("href", "src"):
            if attrs.get(key) is not None and tag in ("a", "link", "img", "script", "area", "iframe", "source"):
                self.links.append(attrs[key])


def broken_links(site: Path) -> list[str]:
    """Every href/src of the site's HTML without a scheme whose file, or whose #anchor, does not exist."""
    pages: dict[Path, _Page] = {}
    for path in site.rglob("*.html"):
        parser = _Page()
        parser.feed(path.read_text(encoding="utf-8", errors="replace"))
        pages[path.resolve()] = parser
    broken = []
    for path, parser in pages.items():
        for link in parser.links:
            parts = urlsplit(link)
            if parts.scheme or link.startswith("//"):
                continue  # external: not ours to check
            target = path if not parts.path else (path.parent / unquote(parts.path)).resolve()
            if target.is_dir():
                target = target / "index.html"
            if not target.exists():
                broken.append(f"{path.relative_to(site.resolve())}: {link} (no such file)")
                continue
            anchor = unquote(parts.fragment)
            if anchor and target.suffix == ".html" and anchor not in pages[target].ids:
                broken.append(f"{path.relative_to(site.resolve())}: {link} (no anchor #{anchor})")
    return broken


def test_the_link_checker_finds_missing_files_and_anchors(tmp_path):
    (tmp_path / "sub").mkdir()
    (tmp_path / "index.html").write_text('<a href="sub/page.html#here">ok</a> <a href="#top">ok</a> <p id="top"></p>'
                                         '<a href="https://example.org/x">external</a> <a href="#">top</a>'
                                         '<a href="sub/">dir</a> <img src="gone.png">'
                                         '<a href="sub/page.html#nowhere">bad anchor</a> <a href="missing.html">bad</a>')
    (tmp_path / "sub" / "page.html").write_text('<h1 id="here">x</h1> <a href="../index.html#top">back</a>')
    (tmp_path / "sub" / "index.html").write_text("<p>dir index</p>")
    assert sorted(broken_links(tmp_path)) == ["index.html: gone.png (no such file)",
                                              "index.html: missing.html (no such file)",
                                              "index.html: sub/page.html#nowhere (no anchor #nowhere)"]


def test_every_internal_link_of_the_built_site_resolves():
    site = Path(os.environ.get("QUICKRELEASE_DOCS_HTML", DOCS / "_build" / "html"))
    if "QUICKRELEASE_DOCS_HTML" not in os.environ and not (site / "index.html").exists():
        pytest.skip("no built site: sphinx-build -W -b html docs docs/_build/html (CI builds it)")
    assert (site / "index.html").exists(), f"no site at {site}"
    assert len(list(site.rglob("*.html"))) > 20
    assert broken_links(site) == []
