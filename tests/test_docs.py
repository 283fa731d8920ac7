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
# A ``$ quickrelease ...`` line is a command a reader pastes: it must parse whole with today's command line (options
# exist, values have the right type and choice, no hidden old option names) and, with QUICKRELEASE_SLOW=1, run.
# An inline `quickrelease ...` (a synopsis with placeholders such as CASE.toml [--out DIR]) must name real options.

SOURCES = [*PAGES, *sorted(p for p in DOCS.rglob("*.rst") if "_build" not in p.parts), ROOT / "README.md"]


def _command_lines():
    lines = []
    for page in SOURCES:
        text = page.read_text(encoding="utf-8")
        rows = text.splitlines()
        for i, row in enumerate(rows):
            line = row.strip()
            if not line.startswith("$ quickrelease"):
                continue
            while line.endswith("\\") and i + 1 < len(rows):  # continued lines
                i += 1
                line = line[:-1] + " " + rows[i].strip()
            lines.append((f"{page.relative_to(ROOT)}:{i + 1}", line[2:].split(" | ")[0], True))
        for line in re.findall(r"`(quickrelease [a-z]+ [^`]*)`", text):
            lines.append((str(page.relative_to(ROOT)), line, False))
        for block in re.finditer(r"^```(?:bash|sh|shell)\n(.*?)^```", text, re.S | re.M):  # bare lines of a shell block
            first = text[:block.start()].count("\n") + 2
            for j, row in enumerate(block.group(1).splitlines()):
                if row.startswith("quickrelease "):
                    command = row.split("  #")[0].split(" # ")[0].split(" > ")[0].split(" | ")[0].strip()
                    lines.append((f"{page.relative_to(ROOT)}:{first + j}", command, True))
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


def parse_faults(line: str) -> list[str]:
    """What keeps ``line`` from parsing whole with today's command line: an unknown command or option, a value of
    the wrong type or choice (click's message), an old (hidden) option name. Empty: it parses."""
    group = typer.main.get_command(app)
    args = shlex.split(line)[1:]
    try:
        ctx = group.make_context("quickrelease", list(args), resilient_parsing=False)
        protected = getattr(ctx, "protected_args", None) or getattr(ctx, "_protected_args", [])
        name, *rest = list(protected) + list(ctx.args)
        sub = group.get_command(ctx, name)
        if sub is None:
            return [f"no command {name!r}"]
        sub.make_context(name, list(rest), parent=ctx)  # raises on an unknown option, a bad value or choice
    except Exception as exc:  # click's usage errors
        return [" ".join(str(exc).split()) or type(exc).__name__]
    hidden = {opt for p in sub.params if getattr(p, "hidden", False) for opt in p.opts}
    used = {a.split("=")[0] for a in rest if a.startswith("-")}
    return [f"{opt} is an old option name" for opt in sorted(used & hidden)]


def test_the_docs_show_command_lines():
    assert len(COMMAND_LINES) >= 20 and sum(full for *_, full in COMMAND_LINES) >= 5


@pytest.mark.parametrize("where, line, full", COMMAND_LINES)
def test_docs_command_lines_name_real_options(where, line, full):
    assert (parse_faults(line) if full else unknown_options(line)) == [], f"{where}: {line}"


def test_the_option_checks_catch_a_wrong_option():
    assert unknown_options("quickrelease simulate --force 1 --alpha0 0.2 --f3 1") == ["--f3"]
    assert unknown_options("quickrelease simulat --force 1") == ["simulat"]
    assert parse_faults("quickrelease simulate --energy 3kJ --alpha0 0.2 --method euler")  # not a choice
    assert parse_faults("quickrelease uq c.toml --samples many")  # not an integer
    assert parse_faults("quickrelease sweep c.toml --grid alpha0=0.1:0.3:3 --file s.nc") == [
        "--file is an old option name"]
    assert parse_faults("quickrelease simulate --energy 3kJ --alpha0 0.2 --method rk") == []


#: Options whose value is a file the command writes (it need not exist beforehand).
_OUTPUT_OPTIONS = {"--out", "-o", "--file", "--case-out"}


def input_files(line: str) -> list[str]:
    """The case files and records (``.toml``, ``.csv``) a command line reads: every such word that is not the value
    of an output option, nor a placeholder of a synopsis (``CASE.toml``, ``<case.toml>``)."""
    words = shlex.split(line.split(" | ")[0].split(" > ")[0].split(" #")[0])
    out = []
    for prev, word in zip(words, words[1:], strict=False):
        if (word.endswith((".toml", ".csv")) and prev not in _OUTPUT_OPTIONS and "<" not in word
                and not re.fullmatch(r"[A-Z_]+\.(toml|csv)", word.rsplit("/", 1)[-1])):
            out.append(word)
    return out


def test_the_input_file_check_sees_a_bare_name():
    assert input_files("quickrelease uq uq_paper.toml --samples 10 --out uq") == ["uq_paper.toml"]
    assert input_files("quickrelease synth examples/paper.toml --file rec.csv") == ["examples/paper.toml"]
    assert input_files("quickrelease run CASE.toml [--out DIR]") == []


@pytest.mark.parametrize("where, line, full", COMMAND_LINES)
def test_documented_commands_read_files_that_exist_from_the_root(where, line, full):
    """Pasted at the repository's root, every file a documented command reads is there (three guide commands named
    bare case files that exist only inside examples/)."""
    missing = [name for name in input_files(line) if not (ROOT / name).is_file()]
    assert missing == [], f"{where}: {line}"


GALLERY = sorted((DOCS / "examples").glob("plot_*.py"))


@pytest.mark.parametrize("script", GALLERY, ids=[p.name for p in GALLERY])
def test_a_gallery_script_outside_a_clone_says_what_it_needs(script, tmp_path, monkeypatch):
    """A downloaded gallery script (or notebook) run outside a clone: one sentence saying what it needs, not a bare
    StopIteration from the search for the examples/ folder; inside a clone (the gallery build) it finds it."""
    import runpy

    text = script.read_text(encoding="utf-8")
    if "EXAMPLES" not in text:
        pytest.skip("needs no files of the repository")
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exc:
        runpy.run_path(str(script), run_name="__gallery__")
    assert "examples/" in str(exc.value.code) and "clone" in str(exc.value.code)
    head = text[:text.index("if EXAMPLES is None")]  # the search itself, run where the gallery runs
    monkeypatch.chdir(DOCS / "examples")
    found = {}
    exec(compile(head, str(script), "exec"), found)  # noqa: S102 - the imports and the search only
    assert found["EXAMPLES"] == ROOT / "examples"


@pytest.mark.slow
@pytest.mark.skipif(not os.environ.get("QUICKRELEASE_SLOW"), reason="runs every documented command: slow")
@pytest.mark.parametrize("where, line", [(w, c) for w, c, full in COMMAND_LINES if full])
def test_documented_command_runs(where, line, tmp_path):
    """As a newcomer would paste it, from the repository's root (a folder laid out as it: examples/ and nothing
    else; no bare case files beside it, as a command naming one without examples/ found them before)."""
    import shutil
    import subprocess
    import sys

    if " bench" in line and "--quick" not in line:
        pytest.skip("the full benchmark (minutes, a 1e8-sample Dask run): `bench --quick` runs here")
    shutil.copytree(ROOT / "examples", tmp_path / "examples")  # the repository root's layout, nothing more
    r = subprocess.run([sys.executable, "-m", "quickrelease", *shlex.split(line)[1:]], cwd=tmp_path,
                       capture_output=True, text=True, timeout=900)
    expected_failure = "--mass-model lumped" in line and "identify" in line  # shown failing
    assert (r.returncode == 2) if expected_failure else (r.returncode == 0), f"{where}: {r.stderr[-2000:]}"


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


# --- equations of a built site ------------------------------------------------------------------------------------

def math_pages() -> list[Path]:
    """The pages whose Markdown writes $...$ mathematics outside code."""
    found = []
    for page in PAGES:
        prose = re.sub(r"^```.*?^```", "", page.read_text(encoding="utf-8"), flags=re.S | re.M)
        if re.search(r"\$[^$\s][^$\n]*\$", re.sub(r"`[^`\n]*`", "", prose)):
            found.append(page)
    return found


def unrendered_math(site: Path) -> list[str]:
    """The pages whose $...$ mathematics the built HTML does not hand to MathJax: no math element, no MathJax
    script, or TeX left as text between dollars."""
    bad = []
    for page in math_pages():
        html_path = site / page.relative_to(DOCS).with_suffix(".html")
        html = html_path.read_text(encoding="utf-8") if html_path.exists() else ""
        body = re.sub(r"<(script|pre)\b.*?</\1>", "", html, flags=re.S)
        if ('class="math notranslate nohighlight"' not in html or "mathjax" not in html.lower()
                or re.search(r"\$[^$<\s][^$<]*\\[A-Za-z]+[^$<]*\$", body)):
            bad.append(str(page.relative_to(DOCS)))
    return bad


def test_every_equation_of_the_built_site_is_typeset():
    site = Path(os.environ.get("QUICKRELEASE_DOCS_HTML", DOCS / "_build" / "html"))
    if "QUICKRELEASE_DOCS_HTML" not in os.environ and not (site / "index.html").exists():
        pytest.skip("no built site: sphinx-build -W -b html docs docs/_build/html (CI builds it)")
    assert len(math_pages()) >= 5
    assert unrendered_math(site) == []


#: The gallery's isolator examples and the truth of their records (examples/make_isolator_records.py, the tests'
#: independent simulator): each printed 95% interval must hold it.
ISOLATOR_GALLERY = {
    "plot_isolator_pendulum.py": {"radius_m": 2.5, "period_s": 2 * 3.141592653589793 * (2.5 / 9.80665) ** 0.5},
    "plot_isolator_lead_rubber.py": {"Kd_N_m": 1.6e6, "Qd_N": 4.0e5, "dy_m": 0.025, "damping_ratio": 0.02},
    "plot_isolator_fluid_damper.py": {"period_s": 2.5, "friction_N": 0.005 * 8.0e5 * 9.80665,
                                      "damping_coefficient": 1.0e5, "damping_exponent": 0.4},
    "plot_isolator_lead_rubber_damper.py": {"Kd_N_m": 1.6e6, "Qd_N": 4.0e5, "dy_m": 0.025, "shape": 1.0,
                                            "damping_coefficient": 2.0e5, "damping_exponent": 0.5},
}


@pytest.mark.slow
@pytest.mark.skipif(not os.environ.get("QUICKRELEASE_SLOW"), reason="opt-in (QUICKRELEASE_SLOW=1): 30-45 s of CPU "
                    "each; CI's sphinx build runs them (and fails on an error) within its 15 minutes")
@pytest.mark.parametrize("name", sorted(ISOLATOR_GALLERY))
def test_an_isolator_gallery_example_runs_and_its_intervals_hold_the_truth(name, monkeypatch, capsys):
    """As the gallery runs it (in docs/examples/, 30-45 s of CPU each): the figures drawn, and each printed 95%
    interval holding the value its synthetic record was made with."""
    import runpy

    import matplotlib.pyplot as plt

    monkeypatch.chdir(DOCS / "examples")
    found = runpy.run_path(str(DOCS / "examples" / name), run_name="__gallery__")
    printed = capsys.readouterr().out
    assert isinstance(found["fig"], plt.Figure)
    plt.close("all")
    for key, truth in ISOLATOR_GALLERY[name].items():
        row = re.search(rf"^{key}\s+\S+\s+95% interval \[(\S+), (\S+)\]", printed, re.M)
        assert row is not None, f"{key} not printed with an interval:\n{printed}"
        assert float(row.group(1)) <= truth <= float(row.group(2)), row.group(0)
