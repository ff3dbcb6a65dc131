"""ORDSLAM sequence descriptions: the scenario catalog, capture times, and what a file's path or
the folder's ``catalog.csv`` says about a sequence (scenario, time of day, depth mode).

File names are not documented by the dataset, so a path (below the dataset folder: every folder of
it, however deep, and the file name) is read strictly, token by token (tokens are separated by ``/``,
``_``, spaces and dots; matching ignores case):

* scenario: ``s5``, ``sc5``, ``scen5``, ``scenario5`` (also ``scenario-5``, ``scenario_5``);
* time of day: ``13-00``, ``13:00``, ``13h00``, ``13h`` (hours 0-23, minutes 00-59);
* depth mode: ``fill`` / ``filled`` or ``standard`` / ``std``.

Any other token is ignored: digits elsewhere (``v2``, ``seq01``, ``run3``) are never read as a
time or a scenario. A field that no token gives, or that two tokens give differently, is
``unknown`` with a :class:`~lorisnb.errors.LorisWarning` naming the file and the forms expected;
so is a scenario number outside the dataset page's 1-6.

A ``catalog.csv`` (columns ``file,scenario,time,depth_mode`` and optionally ``fps``; ``file`` is
the path relative to the folder, or a bare file name when only one ground-truth file has it)
overrides the names; its ``fps`` (frames per second of a file of frame numbers, and of that file's
estimates) overrides the one given for the whole folder, for folders of mixed frame rates. Its
values are checked when the folder is opened: a bad one is a :class:`~lorisnb.errors.ParseError`
naming ``catalog.csv``, the row, the column and the form expected.
"""

from __future__ import annotations

import os
import re
import warnings
from dataclasses import dataclass
from pathlib import Path, PurePath

import numpy as np
import pandas as pd

from lorisnb.errors import LorisWarning, ParseError, ValidationError


@dataclass(frozen=True)
class Scenario:
    number: int
    difficulty: str
    motion: str


#: Motion scenarios as listed on the dataset page (six; ``ordslam-facts.md``). The published
#: Table 3 calls 5 "difficult" and 6 "very difficult" (``../shared/data/published/README.md``).
SCENARIOS: dict[int, Scenario] = {
    1: Scenario(1, "simple", "smooth rotation in a circle without translation"),
    2: Scenario(2, "simple", "vertical or horizontal translation without rotation"),
    3: Scenario(3, "simple", "vertical or horizontal translation, returning to the start position"),
    4: Scenario(4, "medium", "moving towards / away from the scene without rotation"),
    5: Scenario(5, "difficult", "smooth free motion (translation and rotation)"),
    6: Scenario(6, "very difficult", "free motion with shaking or strong wind"),
}
#: The paper's own list has five scenarios (no separate "returning" one): paper number -> page number.
PAPER_TO_PAGE = {1: 1, 2: 2, 3: 4, 4: 5, 5: 6}

CATALOG_COLUMNS = ("file", "scenario", "time", "depth_mode", "fps")
EXPECTED_SCENARIO = "a scenario token s1..s6 (also sc5, scen5, scenario5)"
EXPECTED_TIME = "a time of day HH-MM, HH:MM, HHhMM or HHh (e.g. 13-00, 20h)"
EXPECTED_DEPTH = "a depth mode fill, filled, standard or std"


def scenario(number: int, numbering: str = "page") -> Scenario:
    """The scenario with this number, in the dataset page's numbering (1-6) or the paper's (1-5)."""
    how = str(numbering).strip().lower() if isinstance(numbering, str) else numbering
    if how not in ("page", "paper"):
        raise ValidationError(f"numbering={numbering!r}: expected 'page' (the dataset page's 1-6) or 'paper' (the "
                              "paper's 1-5)")  # fmt: skip
    n = PAPER_TO_PAGE.get(number) if how == "paper" else number
    if isinstance(number, bool) or n not in SCENARIOS:
        valid = sorted(PAPER_TO_PAGE) if how == "paper" else sorted(SCENARIOS)
        raise ValidationError(f"no ORDSLAM scenario {number!r} in the {how} numbering; expected one of {valid}")
    return SCENARIOS[n]


def light_period(time: str | float | None) -> str:
    """Illumination class of a capture time (a time token as :func:`parse_time` reads it:
    ``"13:00"``, ``"13-00"``, ``"13h"``; or hours as a number, 0 to 24): ``day`` (07-17 h), ``dusk``
    (17-20 h, low sun) or ``night`` (20 h and later, before 07 h); ``unknown`` for None or NaN."""
    if time is None:
        return "unknown"
    if isinstance(time, str):
        text = parse_time(time)
        if text is None:
            raise ValidationError(f"time={time!r}: {EXPECTED_TIME}")
        h, _, m = text.partition(":")
        hours = int(h) + int(m) / 60
    else:
        try:
            hours = float(time)
        except (TypeError, ValueError):
            raise ValidationError(f"time={time!r}: {EXPECTED_TIME}, or hours as a number") from None
        if np.isnan(hours):
            return "unknown"
        if not 0 <= hours < 24 or isinstance(time, bool):
            raise ValidationError(f"time={time!r}: hours from 0 to 24 (not 24), or {EXPECTED_TIME}")
    if 7 <= hours < 17:
        return "day"
    if 17 <= hours < 20:
        return "dusk"
    return "night"


_SEP = r"(?:^|(?<=[/_\s.]))"  # a token starts at the start or after a separator ...
_END = r"(?=$|[/_\s.])"  # ... and ends at the end or before one
_SCEN = re.compile(_SEP + r"(?:scenario|scen|sc|s)[-_]?([0-9]+)" + _END, re.I)
_TIME = re.compile(_SEP + r"([01]?[0-9]|2[0-3])(?:[-:h]([0-5][0-9])|h)" + _END, re.I)
_DEPTH = re.compile(_SEP + r"(fill(?:ed)?|standard|std)" + _END, re.I)


def parse_time(text: str) -> str | None:
    """``HH:MM`` from one time token (``13-00``, ``13:00``, ``13h00``, ``13h``, any case), else None."""
    m = _TIME.fullmatch(text.strip())
    return None if m is None else f"{int(m.group(1)):02d}:{m.group(2) or '00'}"


def parse_depth(text: str) -> str | None:
    """``fill`` or ``standard`` from one depth-mode token (any case), else None."""
    m = _DEPTH.fullmatch(text.strip())
    return None if m is None else ("fill" if m.group(1).lower().startswith("fill") else "standard")


def _one(values: set, field: str, expected: str, problems: list[str]) -> object | None:
    if len(values) == 1:
        return next(iter(values))
    problems.append(
        f"{field}: "
        + (f"no {field} token" if not values else f"tokens disagree ({sorted(values)})")
        + f"; expected {expected}"
    )
    return None


def _from_name(p: PurePath) -> tuple[int | None, str | None, str | None]:
    # every part of the path (below the dataset folder, as OrdslamFolder.describe gives it), token by
    # token: scenario5/13-00/fill/groundtruth.txt kept only 13-00/fill/groundtruth and lost its scenario
    text = "/".join(part for part in p.with_suffix("").parts if part != p.anchor)
    problems: list[str] = []
    sc = _one({int(m.group(1)) for m in _SCEN.finditer(text)}, "scenario", EXPECTED_SCENARIO, problems)
    time = _one({parse_time(m.group(0)) for m in _TIME.finditer(text)}, "time of day", EXPECTED_TIME, problems)
    depth = _one({parse_depth(m.group(0)) for m in _DEPTH.finditer(text)}, "depth mode", EXPECTED_DEPTH, problems)
    if sc is not None and sc not in SCENARIOS:
        problems.append(f"scenario {sc} is not one of the dataset page's scenarios 1-6")
        sc = None
    if problems:
        warnings.warn(
            f"{p.as_posix()}: could not read from the name: {'; '.join(problems)} (unknown in the tables; "
            "a catalog.csv next to the files can say it)",
            LorisWarning,
            stacklevel=3,
        )
    return sc, time, depth  # type: ignore[return-value]


def describe_sequence(name: str | os.PathLike, catalog: pd.DataFrame | None = None) -> dict:
    """Scenario, difficulty, motion, capture time, light period and depth mode of a sequence, from
    the catalog if it lists the file (by its path relative to the folder, as
    :func:`read_catalog` resolves it), else from tokens of its path (see the module docstring;
    warns when a field cannot be read)."""
    p = PurePath(name)
    info = dict(
        file=p.name, scenario=np.nan, difficulty="unknown", motion="", time=None, light="unknown", depth_mode="unknown"
    )
    fps = None
    listed = catalog[catalog["file"] == p.as_posix()] if catalog is not None else None
    if listed is not None and len(listed):
        row = listed.iloc[0]
        sc = int(row["scenario"]) if pd.notna(row.get("scenario")) else None
        time = str(row["time"]) if pd.notna(row.get("time")) else None
        depth = str(row["depth_mode"]) if pd.notna(row.get("depth_mode")) else None
        fps = float(row["fps"]) if pd.notna(row.get("fps")) else None
    else:
        sc, time, depth = _from_name(p)
    if sc is not None and sc in SCENARIOS:
        info.update(scenario=sc, difficulty=SCENARIOS[sc].difficulty, motion=SCENARIOS[sc].motion)
    info.update(time=time, light=light_period(time), depth_mode=depth or "unknown", fps=fps)
    return info


def read_catalog(path: str | os.PathLike, groundtruth: list[str]) -> pd.DataFrame:
    """``catalog.csv`` checked and normalized: ``file`` as the ground truth's path relative to the
    folder (``groundtruth``: those paths, ``/``-separated), ``scenario`` 1-6 (the dataset page's
    numbering), ``time`` as ``HH:MM``, ``depth_mode`` ``fill`` or ``standard``, the optional ``fps``
    a positive number (the file's frame rate); empty cells stay unknown (fps: the folder's). Raises ParseError naming the file, the row (its line) and the column."""
    spath = str(path)
    try:
        df = pd.read_csv(path, dtype=str, skipinitialspace=True)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise ParseError(
            spath, None, f"not a CSV table ({exc}); expected columns {', '.join(CATALOG_COLUMNS)}"
        ) from None
    df.columns = [str(c).strip() for c in df.columns]
    unknown = [c for c in df.columns if c not in CATALOG_COLUMNS]
    if "file" not in df.columns or unknown:
        what = f"unknown column(s) {unknown}" if unknown else "no column 'file'"
        raise ParseError(
            spath, 1, f"{what}; expected columns {', '.join(CATALOG_COLUMNS)} (file required, fps optional)"
        )
    by_name: dict[str, list[str]] = {}
    for g in groundtruth:
        by_name.setdefault(PurePath(g).name, []).append(g)
    known = set(groundtruth)
    rows: list[dict] = []
    seen: dict[str, int] = {}
    for i, rec in enumerate(df.to_dict("records")):
        line = i + 2  # line 1 is the header

        def bad(column: str, value: object, expected: str, line: int = line) -> ParseError:
            return ParseError(spath, line, f"row {line - 1}, column {column}: {value!r}; expected {expected}")

        cell = {k: (str(v).strip() if isinstance(v, str) and v.strip() else None) for k, v in rec.items()}
        name = cell["file"]
        if name is None:
            raise bad("file", rec["file"], "the path of a ground-truth file relative to the folder")
        name = Path(name).as_posix()
        if name not in known:
            found = by_name.get(name, []) if "/" not in name else []
            if len(found) != 1:
                why = (
                    f"several ground-truth files are named so ({', '.join(found)})"
                    if found
                    else "no such ground-truth file"
                )
                raise bad("file", cell["file"], f"the path of one ground-truth file relative to the folder; {why}")
            name = found[0]
        if name in seen:
            raise bad("file", cell["file"], f"each file once (already on row {seen[name] - 1})")
        seen[name] = line
        text = cell.get("scenario")
        sc: int | None = None
        if text is not None:
            if not re.fullmatch(r"[0-9]+(?:\.0*)?", text) or int(float(text)) not in SCENARIOS:
                raise bad("scenario", text, "a scenario number 1-6 (the dataset page's numbering)")
            sc = int(float(text))
        time = cell.get("time")
        if time is not None and re.fullmatch(r"[01]?[0-9]|2[0-3]", time):
            time = f"{int(time):02d}:00"  # a whole hour
        elif time is not None and (time := parse_time(time)) is None:
            raise bad("time", cell["time"], EXPECTED_TIME + " or a whole hour 0-23")
        depth = cell.get("depth_mode")
        if depth is not None and (depth := parse_depth(depth)) is None:
            raise bad("depth_mode", cell["depth_mode"], EXPECTED_DEPTH)
        fps = cell.get("fps")
        rate: float | None = None
        if fps is not None:
            try:
                rate = float(fps)
            except ValueError:
                rate = None
            if rate is None or not (np.isfinite(rate) and rate > 0):
                raise bad("fps", fps, "a positive number of frames per second (empty: the folder's fps)")
        rows.append(dict(file=name, scenario=sc, time=time, depth_mode=depth, fps=rate))
    return pd.DataFrame(rows, columns=list(CATALOG_COLUMNS))
