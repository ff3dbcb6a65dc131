"""``python -m lorisnb.cli``: the command line."""

from . import run

run()
