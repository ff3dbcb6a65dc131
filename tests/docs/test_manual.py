"""The manual (``make docs``: docs/build.py): the pages it generates from the code, and the built
site in headless Chromium, offline (marker ``browser``: it opens build/docs/, which CI's `make docs`
builds before `make test-browser`)."""

from __future__ import annotations

import argparse
import importlib.util
import os
import re
from pathlib import Path

import nbformat
import pytest
from browser import need_chromium, offline_pages

from lorisnb.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]
SITE = Path(os.environ.get("LORISNB_DOCS", ROOT / "build" / "docs"))
#: hosts that serve scripts, styles and fonts to pages (none may appear in a built page)
#: A URL naming a CDN: ``//`` then a host with a dot (which base64 never holds: an embedded image's
#: text may have "//" and, further on, "cdn"), then the CDN's name anywhere in the URL
CDN = re.compile(
    r"(?:https?:)?//(?=[A-Za-z0-9-]+\.[A-Za-z0-9])[^\s\"'<>]*"
    r"(?:cdn|jsdelivr|unpkg|googleapis|gstatic|bootstrapcdn|cloudflare)[^\s\"'<>]*",
    re.I,
)


def _module(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def build():
    return _module(ROOT / "docs" / "build.py", "lorisnb_docs_build")


def subcommands() -> list[str]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return list(sub.choices)


def test_the_readme_tour_runs_on_the_parser():
    """Every ``lorisnb ...`` line of the README's tour is a command the parser accepts as written."""
    readme = (ROOT / "README.md").read_text()
    tour = readme.split("## A short tour", 1)[1].split("```sh", 1)[1].split("```", 1)[0]
    lines = [line.split("#", 1)[0].split() for line in tour.splitlines() if line.startswith("lorisnb ")]
    assert {words[1] for words in lines} >= {"evaluate", "sweep", "compare", "diff", "report"}, lines
    parser = build_parser()
    for words in lines:
        args = parser.parse_args(words[1:])  # a usage error would exit 2 here
        assert args.command == words[1]


def test_the_readmes_error_rates_are_the_guides_measured_ones():
    """The README's table of decision error rates is typed once, in the guides, from ``make
    calibrate``'s output: the front page quotes the regression guide's false alarms (model "real")
    and the comparing guide's false claims for every trial count, not numbers of its own."""
    readme = (ROOT / "README.md").read_text()
    gate = (ROOT / "docs/guide/regression-gating.md").read_text()
    compare = (ROOT / "docs/guide/comparing.md").read_text()
    rows = re.findall(r"^\| (\d+) \| ([\d.]+ %) \| ([\d.]+ %) \|$", readme, re.M)
    assert [r[0] for r in rows] == ["1", "3", "5"], rows
    for trials, diff_rate, compare_rate in rows:
        assert re.search(rf"^\| real \| {trials} \| \*\*{re.escape(diff_rate)}\*\* ", gate, re.M), (trials, diff_rate)
        assert re.search(rf"^\| {trials} \| \*\*{re.escape(compare_rate)}\*\* ", compare, re.M), (trials, compare_rate)


def test_layers_table_holds_every_sub_package_and_what_it_may_import(build):
    table = build.layers_table()
    for layer in build.LAYERS:
        assert f"### `lorisnb.{layer}`" in table
        for sub in (ROOT / "lorisnb" / layer).iterdir():
            if (sub / "__init__.py").is_file():
                row = next(line for line in table.splitlines() if f"`lorisnb.{layer}.{sub.name}`" in line)
                assert row.count(" | ") == 2, row  # holds | may import: no cell split by a stray bar
    # what the docstrings say, not a summary of them
    row = next(line for line in table.splitlines() if line.startswith("| {mod}`lorisnb.core.stats` |"))
    assert "none of them imports it (enforced)" in row
    row = next(line for line in table.splitlines() if line.startswith("| {mod}`lorisnb.io.parsing` |"))
    assert "no reader or dataset (enforced)" in row
    # reST roles become MyST roles, relative names absolute
    assert "{mod}`lorisnb.io.parsing.scanner`" in row and ":mod:" not in table


def test_package_pages_list_every_module_and_its_public_functions(build):
    pages = {".".join(p.relative_to(ROOT).parts): p for p in build.packages()}
    assert "lorisnb.core.metrics" in pages and "lorisnb.cli" in pages
    text = build.package_page(pages["lorisnb.core.metrics"])
    assert ".. py:module:: lorisnb.core.metrics.openloris" in text
    assert "- ``correctness``: Eq. (1): c = (ATE <= eps) and (AOE <= phi)." in text
    # absolute values are escaped (not reST substitutions), inline literals left as they are
    assert build.rst_text("|T| and ``a|b``") == "\\|T\\| and ``a|b``"


def test_staged_notebook_writes_into_the_build_and_hides_it(build, tmp_path):
    source = ROOT / "notebooks" / "metrics_primer.ipynb"
    build.stage_notebook(source, tmp_path / "nb.ipynb", tmp_path / "out")
    nb = nbformat.read(tmp_path / "nb.ipynb", as_version=4)
    at = next(i for i, c in enumerate(nb.cells) if "parameters" in c.metadata.get("tags", []))
    cell = nb.cells[at + 1]
    assert cell.source.startswith(f"output_dir = {str(tmp_path / 'out')!r}")
    assert cell.metadata["tags"] == ["remove-cell"]
    assert len(nb.cells) == len(nbformat.read(source, as_version=4).cells) + 1


def test_every_guide_page_is_in_the_manual_in_reading_order(build, tmp_path):
    """index.md's ``guide/*``: the known pages in reading order, then any page another worker adds."""
    (tmp_path / "guide").mkdir()
    (tmp_path / "notebooks").mkdir()
    for name in [*build.GUIDE_ORDER, "zeta", "alpha-new"]:
        (tmp_path / "guide" / f"{name}.md").write_text(f"# {name}\n")
    (tmp_path / "notebooks" / "lifelong_benchmark.ipynb").write_text("{}")
    (tmp_path / "notebooks" / "metrics_primer.ipynb").write_text("{}")
    index = build.reading_order((ROOT / "docs" / "index.md").read_text(), tmp_path)
    guide = [line for line in index.splitlines() if line.startswith("guide/")]
    assert guide == [f"guide/{n}" for n in [*build.GUIDE_ORDER, "alpha-new", "zeta"]]
    notebooks = [line for line in index.splitlines() if line.startswith("notebooks/")]
    assert notebooks == ["notebooks/metrics_primer", "notebooks/lifelong_benchmark"]  # a report's order
    # and the checkout's own pages are all in GUIDE_ORDER's list or follow it
    pages = {p.stem for p in (ROOT / "docs" / "guide").glob("*.md")}
    assert set(build.GUIDE_ORDER) <= pages, set(build.GUIDE_ORDER) - pages


def test_build_refuses_a_folder_it_did_not_make(build, tmp_path, capsys):
    mine = tmp_path / "docs"
    mine.mkdir()
    (mine / "notes.txt").write_text("kept")
    assert build.main([str(mine)]) == 2  # refused before anything is built
    assert "lorisnb did not create it" in capsys.readouterr().err
    assert (mine / "notes.txt").read_text() == "kept" and len(list(mine.iterdir())) == 1


@pytest.mark.browser
@pytest.mark.slow
def test_manual_opens_offline(tmp_path):
    """build/docs from file:// with every http(s) request blocked and recorded: nothing leaves the
    machine, no page refers to a CDN or loads anything from the network, the notebooks' equations read
    as HTML (no TeX: MathJax, where a page has math, is the manual's own), and the command-line
    reference lists every subcommand of the parser."""
    if not (SITE / "index.html").is_file():
        pytest.fail(f"{SITE / 'index.html'} missing: run `make docs` first (`make test-browser` does)")
    need_chromium()
    offline = _module(ROOT / "teaching" / "offline.py", "lorisnb_offline_for_docs")
    html = sorted(SITE.rglob("*.html"))
    assert len(html) > 30, html
    assert offline.remote_references(offline.built_files(SITE)) == []
    cdn = [f"{p.relative_to(SITE)}: {m}" for p in html for m in CDN.findall(p.read_text(errors="replace"))]
    assert cdn == [], cdn

    with offline_pages(tmp_path / "chromium") as pages:
        driver = pages.driver
        pages.open(SITE / "index.html")
        nav = driver.execute_script("return Array.from(document.querySelectorAll('nav a')).map(a => a.textContent)")
        for title in ("Command line", "Python API", "Conventions and semantics", "Architecture"):
            assert any(title in t for t in nav), (title, nav)

        pages.open(SITE / "reference" / "cli.html")
        headings = driver.execute_script(
            "return Array.from(document.querySelectorAll('article h2, article h3')).map(h => h.textContent)"
        )
        for command in subcommands():
            assert any(h.strip().rstrip("#¶").strip() == command for h in headings), (command, headings)
        options = driver.execute_script("return document.querySelector('article').innerText")
        assert "--eps" in options and "--official-interpolation" in options and "--notebooks-dir" in options

        pages.open(SITE / "notebooks" / "metrics_primer.html")
        text = driver.execute_script("return document.querySelector('article').innerText")
        # the paper's equations as HTML (the notebooks hold no TeX: a report's page, without MathJax, reads alike)
        for formula in ("ATEk ≤ ε and AOEk ≤ φ", "CR-T = ( Σ", "CS-R = e"):
            assert formula in " ".join(text.split()), (formula, text[:2000])
        assert "\\frac" not in text and "$$" not in text
        outputs = driver.execute_script("return document.querySelectorAll('.cell_output img').length")
        assert outputs > 0, "metrics_primer: no figure among the outputs (not executed?)"
        pages.open(SITE / "architecture.html")
        pages.open(SITE / "reference" / "api.html")
    assert pages.outside() == [], f"requests that would leave the machine: {pages.outside()}"
    requested = pages.requested
    # a page with math loads MathJax from the manual itself (outside() is empty); the notebooks hold none
    assert not any("mathjax" in u.lower() and "/_static/" not in u for u in requested)
