"""Each command's synopsis in the guides (the ``lorisnb CMD ... [--option ...]`` lines of a ``sh``
block) lists the options its parser offers in ``--help``, and no other: the evaluate synopsis
lacked seven of them (``--kitti-plot``, ``--manifest-outside``, ...), the report synopsis
``--no-progress``, and three commands said they take "every option of lorisnb evaluate" though
each refuses some."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

from lorisnb.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]
#: a synopsis that takes evaluate's options by reference, not by listing them
BY_REFERENCE = "[the options of lorisnb evaluate it applies: lorisnb {cmd} --help]"


def _commands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices


def _offered(p: argparse.ArgumentParser) -> set[str]:
    """The long options ``--help`` shows."""
    return {o for a in p._actions if a.help is not argparse.SUPPRESS for o in a.option_strings
            if o.startswith("--") and o != "--help"}  # fmt: skip


def _synopses() -> dict[str, list[str]]:
    """Each command's synopsis lines, over every guide page."""
    out: dict[str, list[str]] = {}
    for md in sorted((ROOT / "docs" / "guide").glob("*.md")):
        for block in re.findall(r"```sh\n(.*?)```", md.read_text(), re.S):
            cur = None
            for line in block.splitlines():
                m = re.match(r"lorisnb (\w[\w-]*) ", line)
                if m and " [" in line:
                    cur = m.group(1)
                    out.setdefault(cur, []).append(line)
                elif m or not line.startswith(" "):
                    cur = None
                elif cur:
                    out[cur].append(line)
    return out


SYNOPSES = _synopses()


def test_the_main_commands_have_a_synopsis():
    assert {"evaluate", "sweep", "compare", "diff", "history", "report", "verify", "crosscheck"} <= set(SYNOPSES)


@pytest.mark.parametrize("cmd", sorted(SYNOPSES))
def test_a_synopsis_lists_what_the_parser_offers(cmd):
    commands = _commands()
    text = " ".join(SYNOPSES[cmd])
    listed = set(re.findall(r"--[a-z][a-z0-9-]*", text)) - {"--help"}
    offered = _offered(commands[cmd])
    assert listed <= offered, f"{cmd}: the guides list {sorted(listed - offered)}, which --help does not offer"
    if BY_REFERENCE.format(cmd=cmd) in text:  # its own options listed, evaluate's by reference
        offered -= _offered(commands["evaluate"])
    assert offered <= listed, f"{cmd}: --help offers {sorted(offered - listed)}, which its synopsis lacks"
