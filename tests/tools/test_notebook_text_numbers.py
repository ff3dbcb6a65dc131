"""A notebook's number parameter given as text (papermill's ``-r phi 30``) was accepted by the first
cell's check and failed cells later (``f"{phi:g}"``: "Unknown format code 'g' for object of type
'str'"); it is refused up front, saying how to give a number. The report converts text numbers
itself (``-p eps '"1"'`` reaches the notebook as 1.0), and metrics_primer's eps in metres is no
"relative eps" when written as text there."""

from __future__ import annotations

import pytest

from lorisnb.errors import ValidationError
from lorisnb.tools.notebook.params import NUMBERS, check_parameters, check_values
from lorisnb.tools.report.notebooks import declared_by


@pytest.mark.parametrize("name", NUMBERS)
def test_a_number_as_text_is_refused_in_a_notebook(name):
    with pytest.raises(ValidationError, match=rf"{name}='3': a number written as text .*papermill -p {name} 3"):
        check_values({name: "3"}, ["lifelong_benchmark"])


def test_words_stay_words_and_the_report_converts_text_numbers():
    check_values({"eps": "paper", "phi": 30.0, "seed": 3}, ["metrics_primer"])
    declared = declared_by(["metrics_primer"], None)
    got = check_parameters({"eps": "1", "phi": "30"}, declared, ["metrics_primer"])
    assert got["eps"] == 1.0 and got["phi"] == 30.0
