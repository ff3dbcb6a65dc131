"""The command line's parser as the manual's reference shows it (``reference/cli.md``): lorisnb's
own (:func:`lorisnb.cli.build_parser`) with its help texts escaped for reStructuredText, which
sphinx-argparse parses them as (``ape_*`` would open an emphasis, ``ape_`` name a link target)."""

from __future__ import annotations

import argparse
import re

from lorisnb.cli import build_parser


def _escape(text: str | None) -> str | None:
    return None if text is None else re.sub(r"([\\*`_|])", r"\\\1", text)


def _escaped(parser: argparse.ArgumentParser) -> None:
    parser.description = _escape(parser.description)
    parser.epilog = _escape(parser.epilog)
    for action in parser._actions:  # noqa: SLF001 (argparse keeps no public list of a parser's actions)
        if action.help not in (None, argparse.SUPPRESS):
            action.help = _escape(action.help)
        if isinstance(action, argparse._SubParsersAction):  # noqa: SLF001
            for sub in action.choices.values():
                _escaped(sub)
            for choice in action._choices_actions:  # noqa: SLF001 (the sub-commands' one-line help)
                choice.help = _escape(choice.help)


def manual_parser() -> argparse.ArgumentParser:
    """:func:`lorisnb.cli.build_parser`'s parser, help texts escaped for the manual."""
    parser = build_parser()
    _escaped(parser)
    return parser
