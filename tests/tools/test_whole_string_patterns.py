"""Names and addresses are matched whole: a pattern's ``$`` also matches before a trailing newline,
so ``cafe-1-1\\n`` was a sequence name and ``localhost:8786\\n/`` a scheduler address."""

from __future__ import annotations

import pytest

from lorisnb.errors import ValidationError
from lorisnb.tools.challenge.uploads import sequence_of
from lorisnb.tools.evaluation.pool import scheduler_address


def test_sequence_names_are_matched_whole():
    assert sequence_of("cafe-1-2.txt") == ("cafe", 2)
    assert sequence_of("home_1_5_orbslam2.txt") == ("home", 5)
    assert sequence_of("cafe-1-2\n") is None
    assert sequence_of("cafe-1-2\n.txt") is None


def test_scheduler_addresses_are_matched_whole():
    assert scheduler_address("tcp://127.0.0.1:8786") == ("tcp", "127.0.0.1", 8786)
    with pytest.raises(ValidationError, match="not a HOST:PORT address"):
        scheduler_address("127.0.0.1:8786\n/")
