"""``python -m lorisnb.cli``: the command line."""

from lorisnb.cli import run

run()
