"""Names with control and bidirectional characters (a folder named with ESC, a newline, a carriage
return, a tab or U+202E) in every output of diff, history and compare: the terminal, JUnit XML (well
formed: XML 1.0 holds no ESC), GitHub's annotations, Markdown, LaTeX and SVG figures show them
escaped by the one rule (``\\x1b``, ``\\n``, ``\\u202e``), each name distinguishable, nothing in
them acting. JSON and CSV keep them whole (their own quoting holds any character)."""

from __future__ import annotations

import json
import re
import shutil
import xml.etree.ElementTree as ET

import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.cli.text import clean as terminal_clean
from lorisnb.io.writers import write_csv
from lorisnb.tools.decisions.diff import diff_tables, github_annotations, markdown, write_junit
from lorisnb.tools.decisions.escape import (
    clean,
    code_span,
    markdown_cell,
    workflow_data,
    workflow_property,
)

NAMES = ["esc\x1b[31mRED\x1b[0m", "nl\nalg", "cr\rOVER", "tab\talg", "bidi\u202eabc", "osc\x1b]0;T\x07"]
#: What no output for a terminal or a reader may hold: C0 controls, DEL, C1, bidirectional controls.
RAW = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u200e\u200f\u202a-\u202e\u2066-\u2069]")
ODOM = ("cafe-1-1-odom.txt", "cafe-1-2-odom.txt")


@pytest.fixture(scope="module")
def tables(tmp_path_factory, icra20):
    """BASE and CAND per-sequence tables of one algorithm per name in NAMES (the odom cafe files):
    CAND's CR 0.4 lower (regressions) and its ATE halved (improvements)."""
    root = tmp_path_factory.mktemp("ctl")
    one = ln.evaluate([icra20 / "per-seq" / "odom" / f for f in ODOM], progress=False).sequences()
    import pandas as pd

    base = pd.concat([one.assign(algorithm=n, file=[f"{n}/{f}" for f in one["file"]]) for n in NAMES])
    cand = base.assign(cr=(base["cr"] - 0.4).clip(lower=0), ate_rmse=base["ate_rmse"] / 2)
    paths = write_csv(base, root / "base.csv"), write_csv(cand, root / "cand.csv")  # as evaluate --csv writes them
    return base, cand, paths


def test_one_rule_for_every_format():
    """The terminal's clean is the one function; each format escapes its own syntax after it."""
    assert terminal_clean is clean
    assert clean("a\x1b[2Jb\nc\u202ed\te\udcff") == "a\\x1b[2Jb\\nc\\u202ed\\te\\udcff"
    assert workflow_data("50% a\nb\x1b") == "50%25 a\\nb\\x1b"
    assert workflow_property("t: a, b%") == "t%3A a%2C b%25"
    # a backslash escaped too: \\n in the file shows as \n, as in the terminal
    assert markdown_cell("a|b\n<i>&`x`*[l](u)~") == "a\\|b\\\\n&lt;i&gt;&amp;\\`x\\`\\*\\[l\\](u)\\~"
    assert markdown_cell("orbslam2_rgbd") == "orbslam2_rgbd"
    assert code_span("a`b") == "``a`b``" and code_span("`x") == "`` `x ``" and code_span("we ird&<x>") == "`we ird&<x>`"


def test_diff_outputs_escape_every_name_and_xml_is_well_formed(tables, tmp_path, capsys):
    _, _, (base, cand) = tables
    xml, md, js = tmp_path / "d.xml", tmp_path / "d.md", tmp_path / "d.json"
    rc = main(["diff", str(base), str(cand), "--junit", str(xml), "--markdown", str(md), "--json", str(js),
               "--annotations"])  # fmt: skip
    out, err = capsys.readouterr()
    assert rc == 1, err
    for text in (out, err, md.read_text(encoding="utf-8"), xml.read_text(encoding="utf-8")):
        assert not RAW.search(text.replace("\n", "")), RAW.search(text.replace("\n", ""))
    # JUnit: parsed by expat, every name there as the terminal shows it, all distinct
    root = ET.parse(xml).getroot()
    classes = {c.get("classname") for c in root.iter("testcase")}
    assert {f"{clean(n)}.cafe" for n in NAMES} <= classes
    assert any(f.get("type") == "regression" for f in root.iter("failure"))
    # annotations: one line each, a title per name, GitHub's encoding of ':' and ','
    lines = [x for x in out.splitlines() if x.startswith("::")]
    errors = [x for x in lines if x.startswith("::error ")]
    assert errors and all(x.count("::") == 2 for x in lines)
    for n in NAMES:
        assert any(f"title=lorisnb diff%3A regression {clean(n)} cafe" in x for x in errors), n
    # Markdown: one table row per line, 7 cell borders each, the names escaped
    rows = [x for x in md.read_text(encoding="utf-8").splitlines() if x.startswith("| ") and "cafe" in x]
    assert rows and all(len(re.findall(r"(?<!\\)\|", r)) == 7 for r in rows)
    for n in NAMES:
        assert any(r.startswith(f"| {markdown_cell(n)} |") for r in rows), n
    # the terminal's tables and lines: escaped too; JSON keeps the names whole
    assert all(clean(n) in out for n in NAMES)
    assert {r["algorithm"] for r in json.loads(js.read_text())["regressions"]} == set(NAMES)


def test_the_python_writers_escape_as_the_command_line(tables, tmp_path):
    base, cand, _ = tables
    d = diff_tables(base, cand)
    assert d.regressed
    for line in github_annotations(d):
        assert not RAW.search(line) and "\n" not in line
    text = markdown(d, "runs/a\x1bb", "runs/c`d\u202e", "v1\nx")
    assert not RAW.search(text.replace("\n", ""))
    assert "`runs/a\\x1bb` → ``runs/c`d\\u202e`` (code under test: `v1\\nx`)" in text
    out = write_junit(d, tmp_path / "v.xml", force=False)
    cases = ET.parse(out).getroot().iter("testcase")
    assert {c.get("classname") for c in cases} == {f"{clean(n)}.cafe" for n in NAMES}


def test_compare_markdown_and_latex_and_history_figures(tmp_path, icra20, tables, capsys):
    """compare's tables (result folders named with control characters) and history's SVG figures."""
    res = tmp_path / "res"
    for n in NAMES:
        (res / n).mkdir(parents=True)
        for f in ODOM:
            shutil.copy(icra20 / "per-seq" / "odom" / f, res / n / f)
    md, tex = tmp_path / "t.md", tmp_path / "t.tex"
    assert main(["compare", str(res), "--markdown", str(md), "--latex", str(tex), "--no-progress"]) == 0
    out, err = capsys.readouterr()
    for text in (out, err, md.read_text(encoding="utf-8"), tex.read_text(encoding="utf-8")):
        assert not RAW.search(text.replace("\n", ""))
    rows = [x for x in md.read_text(encoding="utf-8").splitlines()[2:] if x.startswith("|")]
    assert sorted(r.split(" | ")[0][2:] for r in rows) == sorted(markdown_cell(n) for n in NAMES)
    assert tex.read_text(encoding="utf-8").count(r"\\") == 1 + len(NAMES)  # the header and one row per name
    _, _, (base, cand) = tables
    figs = tmp_path / "figs"
    assert main(["history", str(base), str(cand), "--out", str(figs), "--metric", "cr"]) == 1
    assert "\x1b" not in capsys.readouterr().out
    svgs = sorted(figs.glob("*.svg"))
    assert svgs
    for svg in svgs:
        ET.parse(svg)  # well formed: no control character of a name in it


def test_any_saved_figure_holds_no_control_character(tmp_path):
    from lorisnb.tools.figures.plotting import save_figure, subplots

    fig, ax = subplots()
    ax.plot([0, 1], [0, 1], label="alg\x1b[31m\u202e")
    ax.legend()
    ax.set_title("two lines\nof a title, one name esc\x1b")
    (svg,) = save_figure(fig, tmp_path, "f", formats=("svg",))
    ET.parse(svg)
    assert ax.get_title() == "two lines\nof a title, one name esc\\x1b"  # its own line break kept
