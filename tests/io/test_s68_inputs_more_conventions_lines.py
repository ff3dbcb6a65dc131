"""A manifest's refused ``[conventions]`` value and reading key name the file, the line and the
manifest's spelling (s68 finding 3): ``change_unit = "mm"`` without a relation said "give a relation
(--relation)" with no line, ``estimate_topic`` with TUM estimates had no line. The line is found by
one rule (the key the spec's message starts with), for every refusal between values."""

from __future__ import annotations

import pytest

from lorisnb.core.spec.evalspec import make_spec
from lorisnb.errors import ParseError, ValidationError
from lorisnb.io.datasets.manifest import read_manifest

HEAD = 'name = "t"\nscene = "s"\n'
SESSION = '\n[[session]]\nname = "a"\ngroundtruth = "gt.txt"\n'


def _read(tmp_path, body: str):
    (tmp_path / "gt.txt").write_text("1 0 0 0 0 0 0 1\n2 1 0 0 0 0 0 1\n")
    path = tmp_path / "m.toml"
    path.write_text(HEAD + body + SESSION)
    return read_manifest(path)


@pytest.mark.parametrize(
    ("body", "line", "said"),
    [
        ('[conventions]\npreset = "evo"\nchange_unit = "mm"\n', 5, "change_unit mm: .*give a relation too \\(relation: "),
        ('estimate_topic = "/odom"\n', 3, "estimate_topic: only for bag files"),
        ('\n[conventions]\npreset = "evo"\nrpe_unit = "f"\nrpe_tolerance = 0.2\n', 7, "rpe_tolerance: only for evo's"),
        ('[conventions]\npreset = "evo"\nmax_gap = 0.3\n', 5, "max_gap: only for interpolation"),
    ],
)  # fmt: skip
def test_refusals_name_the_line_of_their_key(tmp_path, body, line, said):
    with pytest.raises(ParseError, match=rf"m.toml, line {line}: {said}") as caught:
        _read(tmp_path, body)
    assert "--" not in str(caught.value).replace("evo's --change_unit", "")


def test_the_relation_is_named_as_each_surface_spells_it():
    for surface, name in (("cli", "--relation"), ("python", "relation"), ("manifest", "relation")):
        with pytest.raises(ValidationError, match=rf"give a relation too \({name}: trans_part"):
            make_spec("evo", surface=surface, change_unit="mm").refuse_inapplicable("pair", surface=surface)
