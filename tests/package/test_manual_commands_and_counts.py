"""The commands the manual shows run as written, and a count it gives of a real file is the file's.

- ``make TARGET ...`` (README, environment.md, docs/, teaching/'s pages): TARGET is a target of the
  Makefile, every other word a ``VARIABLE=value`` the Makefile reads; an option (``make grade
  --roster roster.csv``, ``make calibrate --power-nights 36``) is GNU make's own, which it rejects.
  The options given through such a variable (``GRADE_ARGS="--roster roster.csv"``) are options of
  the script the Makefile passes it to.
- ``SCRIPT.py --option`` (a script of the repository): the script takes the option.
- docs/guide/many-files.md's profile of "orbslam2 cafe-1" gives its poses: 1,708 (its 1,716 lines
  hold a header too)."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

import lorisnb as ln

ROOT = Path(__file__).resolve().parents[2]
GENERATED = {"release", "submitted", "autograded", "feedback", "graded", "exports", "_build", "node_modules"}
#: an inline code span, or a line of a fenced block (``$ `` prompts dropped)
SPAN = re.compile(r"`([^`\n]+)`")


def pages() -> list[Path]:
    found = [ROOT / "README.md", ROOT / "environment.md", *(ROOT / "docs").rglob("*.md")]
    found += [p for p in (ROOT / "teaching").rglob("*.md") if not GENERATED & set(p.relative_to(ROOT).parts)]
    return sorted(p for p in found if p.is_file())


def commands(text: str) -> list[str]:
    """What a page shows as code: inline spans and the lines of fenced blocks."""
    out, fenced = [], False
    for line in text.splitlines():
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        if fenced:
            out.append(line.strip().removeprefix("$ "))
        else:
            out += SPAN.findall(line)
    return out


def makefile() -> tuple[set[str], dict[str, str]]:
    """The Makefile's targets, and each variable it reads with the recipe line that reads it."""
    text = (ROOT / "Makefile").read_text()
    targets = set()
    for head in re.findall(r"^([A-Za-z0-9_.$() -]+?):(?![=])", text, re.M):
        targets.update(t for t in head.split() if "$" not in t)
    read = {}
    for line in text.splitlines():
        for var in re.findall(r"\$\(([A-Z_][A-Z0-9_]*)\)", line):
            read.setdefault(var, line)
    for var in re.findall(r"^([A-Z_][A-Z0-9_]*)\s*[?:]?=", text, re.M):
        read.setdefault(var, "")
    return targets, read


def script_options(script: Path) -> set[str]:
    return set(re.findall(r"""["'](--[a-z][a-z0-9-]*)["']""", script.read_text()))


def words_after(command: str, head: str) -> list[str]:
    """The words of a shell command after ``head``, up to a comment or the next command."""
    try:
        words = shlex.split(command, comments=True)
    except ValueError:
        words = command.split("#")[0].split()
    words = words[words.index(head) + 1 :] if head in words else []
    ends = [i for i, w in enumerate(words) if w in ("&&", "||", ";", "|", ">", "2>&1")]
    return words[: ends[0]] if ends else words


def make_faults(shown: list[Path]) -> tuple[list[str], int]:
    """What is wrong with each ``make`` command the pages show, and how many there are."""
    targets, read = makefile()
    wrong, seen = [], 0
    for page in shown:
        where = page.relative_to(ROOT) if page.is_relative_to(ROOT) else page
        for command in commands(page.read_text()):
            if not re.match(r"(\S+=\S+\s+)*make\s", command):
                continue
            seen += 1
            for word in words_after(command, "make"):
                if word.startswith("-"):
                    wrong.append(f"{where}: `{command}`: {word} is an option of make, not of the target")
                elif "=" in word:
                    var, value = word.split("=", 1)
                    if var not in read:
                        wrong.append(f"{where}: `{command}`: the Makefile reads no {var}")
                    elif var.endswith("_ARGS") and (script := re.search(r"(\S+\.py)", read[var])):
                        given = {w.split("=")[0] for w in shlex.split(value) if w.startswith("--")}
                        unknown = sorted(given - script_options(ROOT / script.group(1)))
                        if unknown:
                            wrong.append(f"{where}: `{command}`: {script.group(1)} takes no {unknown}")
                elif word not in targets and not word.startswith("<"):
                    wrong.append(f"{where}: `{command}`: the Makefile has no target {word}")
    return wrong, seen


def test_every_make_command_of_the_manual_runs_as_written():
    targets, read = makefile()
    assert {"grade", "calibrate", "bench", "test", "docs"} <= targets and "GRADE_ARGS" in read
    wrong, seen = make_faults(pages())
    assert seen > 20  # the manual's make commands are read
    assert not wrong, "\n".join(wrong)


def test_every_script_option_the_manual_shows_is_the_scripts():
    scripts = {p.name: p for folder in ("benchmarks", "teaching") for p in (ROOT / folder).glob("*.py")}
    wrong, seen = [], 0
    for page in pages():
        for command in commands(page.read_text()):
            for name in re.findall(r"(?:^|[\s/])([\w-]+\.py)\b", command):
                if name not in scripts:
                    continue
                seen += 1
                options = {w.split("=")[0] for w in words_after(command.replace("/", " "), name) if w.startswith("--")}
                unknown = options - script_options(scripts[name])
                if unknown:
                    wrong.append(f"{page.relative_to(ROOT)}: `{command}`: {name} takes no {sorted(unknown)}")
    assert seen >= 3
    assert not wrong, "\n".join(wrong)


def test_the_profiled_file_holds_the_poses_many_files_md_says(icra20):
    """docs/guide/many-files.md profiles a worker on "orbslam2 cafe-1" (the RGB-D per-seq file):
    1,708 poses, read as lorisnb reads them."""
    path = icra20 / "per-seq" / "orbslam2_rgbd" / "cafe_1_1_orbslam2-original.txt"
    poses = ln.read_openloris(path).n_poses
    assert poses == 1708 and len(path.read_text().splitlines()) == 1716
    said = re.search(r"orbslam2 cafe-1, ([\d,]+) poses", (ROOT / "docs" / "guide" / "many-files.md").read_text())
    assert said and int(said.group(1).replace(",", "")) == poses


@pytest.mark.parametrize(
    ("command", "fault"),
    [("make grade --roster roster.csv", "--roster is an option of make"),
     ("make calibrate --power-nights 36", "--power-nights is an option of make"),
     ('make grade GRADE_ARGS="--rooster r.csv"', "teaching/grade.py takes no \\['--rooster'\\]"),
     ("make gradee", "no target gradee"), ("make grade GRADE_ARG=x", "reads no GRADE_ARG")],
)  # fmt: skip
def test_a_command_make_rejects_is_found(command, fault, tmp_path):
    page = tmp_path / "page.md"
    page.write_text(f'Run `{command}` to see, or `make grade GRADE_ARGS="--roster roster.csv"`.\n')
    wrong, seen = make_faults([page])
    assert seen == 2 and wrong and re.search(fault, wrong[0]), wrong
