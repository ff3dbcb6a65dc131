"""The teaching kit's builds open offline and fail loudly (teaching/offline.py, book.py, slides.py,
offline_feedback.py): nothing a page, style sheet or script loads comes from the network; the book
drops sphinx-thebe's scripts; a notebook that fails to execute fails `make book` without replacing
the previous book; each feedback page carries its own MathJax. No notebook is executed; the two
that run the kit's own environment are slow (the `teaching_python` fixture makes .venv-teach)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from test_teaching_kit import _teaching_module

ROOT = Path(__file__).resolve().parents[2]

PAGE = """<html><head>
<link rel="stylesheet" href="_static/local.css" />
<link rel="stylesheet" href="https://cdn.example.org/theme.css" />
<script src="//unpkg.com/x/lib.js"></script>
<script>const THEBE_JS_URL = "https://unpkg.com/thebe@0.8.2/lib/index.js"; const thebe_selector = ".thebe"</script>
<style>@import url(https://fonts.googleapis.com/css?family=Lato:400);</style>
</head><body><svg xmlns="http://www.w3.org/2000/svg"></svg><a href="https://revealjs.com">reveal.js</a>
<!-- http://hakim.se --></body></html>
"""


def test_remote_references_are_scripts_styles_imports_fonts_and_script_urls_not_links(tmp_path):
    offline = _teaching_module("offline")
    (tmp_path / "page.html").write_text(PAGE)
    (tmp_path / "theme.css").write_text(
        "/* http://hakim.se */\n@font-face { src: url('https://fonts.gstatic.com/a.woff2'); }\n"
    )
    (tmp_path / "ok.css").write_text("@import url(./fonts/source-sans-pro/source-sans-pro.css);\n")
    (tmp_path / "lib.js").write_text(
        'var ns = "http://www.w3.org/2000/svg"; load("https://cdn.jsdelivr.net/npm/p@1/x.js");\n'
    )
    found = {line.split(": ", 1)[1] for line in offline.remote_references(offline.built_files(tmp_path))}
    assert found == {
        "https://cdn.example.org/theme.css",
        "//unpkg.com/x/lib.js",
        "https://unpkg.com/thebe@0.8.2/lib/index.js",
        "https://fonts.googleapis.com/css?family=Lato:400",
        "https://fonts.gstatic.com/a.woff2",
        "https://cdn.jsdelivr.net/npm/p@1/x.js",
    }


def test_the_book_pages_lose_sphinx_thebes_scripts(tmp_path):
    book, offline = _teaching_module("book"), _teaching_module("offline")
    thebe = (
        '    <script>const THEBE_JS_URL = "https://unpkg.com/thebe@0.8.2/lib/index.js"; const thebe_selector = ".thebe"</script>\n'
        '    <script async="async" src="_static/sphinx-thebe.js?v=c100c467"></script>\n'
    )
    keep = '    <script defer="defer" src="_static/mathjax/tex-chtml.js?v=f4737972"></script>\n'
    (tmp_path / "lab.html").write_text(f"<head>\n{thebe}{keep}{thebe}</head>\n")
    book.without_thebe(tmp_path)
    assert (tmp_path / "lab.html").read_text() == f"<head>\n{keep}</head>\n"
    assert offline.remote_references([tmp_path / "lab.html"]) == []


def test_a_notebook_that_fails_fails_the_book_and_keeps_the_previous_one(tmp_path, monkeypatch, capsys):
    book = _teaching_module("book")
    out = tmp_path / "book"
    out.mkdir()
    (out / book.BUILD_MARKER).touch()
    (out / "index.html").write_text("the previous, good book")
    mathjax = tmp_path / "mathjax"
    mathjax.mkdir()
    (mathjax / "tex-chtml.js").write_text("// MathJax")
    seen = {}

    def jupyter_book(cmd, check, env):  # what jupyter-book leaves when a notebook fails to execute
        src = Path(cmd[2])
        seen["tmpdir"] = env["TMPDIR"]
        html = src / "_build" / "html"
        (html / "reports").mkdir(parents=True)
        (html / "index.html").write_text("a book with a broken page")
        (html / "reports" / "lab1_lifelong_metrics.err.log").write_text(
            "Traceback ...\nNameError: name 'x' is not defined\n"
        )
        return subprocess.CompletedProcess(cmd, 1)

    monkeypatch.setattr(book, "mathjax_dir", lambda: mathjax)
    monkeypatch.setattr(book.subprocess, "run", jupyter_book)
    assert book.main(out) == 1
    err = capsys.readouterr().err
    assert "lab1_lifelong_metrics.ipynb failed to execute" in err and "NameError: name 'x'" in err
    assert f"{out} is left as it was" in err
    assert (out / "index.html").read_text() == "the previous, good book"
    assert not Path(seen["tmpdir"]).exists(), "the notebooks' temporary folders go with the build's"
    assert book.build_problems(tmp_path / "nothing", 2).startswith("the book did not build: jupyter-book exited with 2")
    (tmp_path / "good").mkdir()
    (tmp_path / "good" / "index.html").write_text("ok")
    assert book.build_problems(tmp_path / "good", 0) is None


@pytest.mark.slow
def test_slides_assets_load_nothing_from_the_network(tmp_path, teaching_python):
    """reveal.js's themes import Google Fonts (simple, the nbconvert default, among them)."""
    code = (
        "import sys, pathlib, slides, offline\n"
        "out = pathlib.Path(sys.argv[1]); slides.assets(out)\n"
        "print('\\n'.join(offline.remote_references(offline.built_files(out))))\n"
        "print('theme', slides.THEME, (out / 'reveal.js' / 'dist' / 'theme' / (slides.THEME + '.css')).is_file())\n"
    )
    r = subprocess.run(
        [str(teaching_python), "-c", code, str(tmp_path / "slides")],
        cwd=ROOT / "teaching",
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.strip() == "theme white True", r.stdout[-3000:]
    css = (tmp_path / "slides" / "reveal.js" / "dist" / "theme" / "white.css").read_text()
    assert "@import url(./fonts/source-sans-pro/source-sans-pro.css)" in css


@pytest.mark.slow
def test_each_feedback_page_carries_its_own_mathjax(tmp_path, teaching_python):
    """`nbgrader release_feedback` hands out the .html files only: a MathJax folder beside them is lost."""
    feedback = tmp_path / "feedback"
    page = feedback / "student" / "lab" / "lab.html"
    page.parent.mkdir(parents=True)
    cdn = '<script src="https://cdnjs.cloudflare.com/ajax/libs/mathjax/2.7.7/MathJax.js?config=TeX-AMS_HTML"></script>'
    page.write_text(f"<html><head>{cdn}</head><body><p>$c(p_k)$</p></body></html>")
    (feedback / "mathjax").mkdir()
    (feedback / "mathjax" / "tex-chtml.js").write_text("// the shared copy of earlier versions")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    for _ in range(2):  # a second run leaves the pages as they are
        r = subprocess.run(
            [str(teaching_python), str(ROOT / "teaching" / "offline_feedback.py"), str(feedback)],
            capture_output=True,
            text=True,
            timeout=300,
            env=env,
        )
        assert r.returncode == 0, r.stderr[-2000:]
    html = page.read_text()
    assert html.count('<script id="lorisnb-mathjax">') == 1 and "cdnjs" not in html and "MathJax" in html
    assert "</script" not in html.split('<script id="lorisnb-mathjax">', 1)[1].split("</script>", 1)[0]
    assert not (feedback / "mathjax").exists()
    offline = _teaching_module("offline")
    assert offline.remote_references([page]) == []
    assert sys.getsizeof(html) < 4e6
