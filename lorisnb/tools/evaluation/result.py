"""What an evaluation returns: the errors of every input evaluated, the failures, and the spec
they were computed under (:class:`~lorisnb.core.spec.evalspec.EvalSpec`), whose thresholds are the
defaults of every table."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from lorisnb.core.lifelong.aggregate import aggregate_scenes, spans_table
from lorisnb.core.lifelong.scoring import pose_table, score_rows
from lorisnb.core.metrics.relative import RPG_FRACTIONS
from lorisnb.core.pipeline.model import (
    EXTRA_COLUMNS,
    SEQUENCE_COLUMNS,
    STAT_COLUMNS,
    Eps,
    FileErrors,
    ScoresOnly,
    check_label,
)
from lorisnb.core.spec.evalspec import THRESHOLD_NAMES, EvalSpec, make_spec
from lorisnb.core.spec.validate import known_keys
from lorisnb.core.trajectory.blocks import threads
from lorisnb.core.trajectory.frames import SCENES
from lorisnb.errors import EvaluationError, ValidationError
from lorisnb.io.datasets.paths import DataPaths, scene_spans
from lorisnb.tools.evaluation.pool import default_jobs
from lorisnb.tools.evaluation.status import exit_status, skipped_only, unscored

if TYPE_CHECKING:
    import pandas as pd


def _same(given: Any, held: Any) -> bool:
    """``given`` is the value the spec holds, of the same type: nothing to check again."""
    return type(given) is type(held) and bool(given == held)


#: A note that many inputs share but for the input it names is said in full for this many of
#: them, then once more with how many others it is about and the first of them
#: (:func:`said_notes`); every note is kept (``Evaluation.warnings``, ``FileErrors.warnings``).
SAME_NOTE_IN_FULL = 3
#: The inputs a shared note's last line names, at most.
SAME_NOTE_NAMED = 10
#: Characters of a note quoted in the line that counts the rest of its kind (its first words).
GIST_CHARS = 40
#: A number in a note (``19``, ``0.600``, ``1e-06``): notes that differ only in them are one kind.
NUMBER = re.compile(r"\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")


def said_notes(files: list[FileErrors]) -> list[str]:
    """The notes of ``files`` as said to the user (issued as warnings, printed by the command
    line): each once, a note's kind in the order its first note came, except that a note the same
    but for the input it names and its
    numbers (a folder of 5,000 short runs, each with "no RPE pair over 1 s (its N matched poses
    span T s)") is said in full for the first
    :data:`SAME_NOTE_IN_FULL` inputs and then in one line with how many more inputs it is about,
    naming the first :data:`SAME_NOTE_NAMED` of them, so that the table and the other notes are
    not lost in thousands of lines."""
    groups: dict[str, list[tuple[str, str]]] = {}
    for f in files:
        names = sorted({str(f.path), f.file, check_label(f.path, f.file)} - {""}, key=len, reverse=True)
        for w in f.warnings:
            shape = w
            for n in names:  # the longest spelling of the input first: a path holds its file label
                shape = shape.replace(n, "\0")
            groups.setdefault(NUMBER.sub("#", shape), []).append((f.file, w))  # each file's own numbers aside
    out: list[str] = []
    for said in groups.values():
        notes = list(dict.fromkeys(w for _, w in said))
        if len(notes) <= SAME_NOTE_IN_FULL + 1:
            out += notes
            continue
        out += notes[:SAME_NOTE_IN_FULL]
        shown = set(notes[:SAME_NOTE_IN_FULL])
        rest = list(dict.fromkeys(label for label, w in said if w not in shown))  # a file once, whatever its notes
        named = ", ".join(rest[:SAME_NOTE_NAMED]) + (", ..." if len(rest) > SAME_NOTE_NAMED else "")
        # which note: its first words after the input's name (two kinds' counting lines were the same text,
        # and the command line, which says each text once, dropped the second)
        gist = notes[SAME_NOTE_IN_FULL - 1].split(": ", 1)[-1]
        gist = gist if len(gist) <= GIST_CHARS else gist[:GIST_CHARS].rsplit(" ", 1)[0] + " ..."
        out.append(f"a note like the one above ('{gist}', numbers aside) {len(notes) - SAME_NOTE_IN_FULL:,} more "
                   f"time(s), about {len(rest):,} input(s): {named} (each note: Evaluation.warnings in Python)")  # fmt: skip
    return out


@dataclass
class Failure:
    """An input that could not be evaluated, with the reason (file, line, what was expected)."""

    path: Path
    error: str
    kind: str
    #: (suite, algorithm, trial) of each run this failure leaves without output: an empty trial
    #: folder's (kind ``empty-trial``), which ``compare`` expects as failed runs of every sequence
    trials: tuple[tuple[str, str, int], ...] = ()


@dataclass
class Evaluation:
    """What :func:`lorisnb.evaluate`, :func:`lorisnb.evaluate_pairs` and
    :func:`lorisnb.evaluate_manifest` return: the errors of every input evaluated, the failures,
    and the spec (``spec``) whose thresholds and RPE step the tables use unless given."""

    errors: list[FileErrors]
    failures: list[Failure]
    root: Path | None = None
    skipped: list[Failure] = field(default_factory=list)
    data: DataPaths | None = None
    spec: EvalSpec = field(default_factory=EvalSpec)
    kind: str = "openloris"  # openloris, pair or manifest
    notes: list[str] = field(default_factory=list)  # one-line notes on the options (harmless ones)

    def __post_init__(self) -> None:
        """Each file's errors record the spec's thresholds, the defaults of this evaluation's tables,
        as they record its RPE settings (``FileErrors.rpe``): ``ln.score(ev.errors)`` and
        ``ln.sweep(ev.errors)`` score them at the setting ``ev.sequences()`` does
        (:func:`lorisnb.core.lifelong.scoring.thresholds_of`)."""
        thresholds = self.thresholds
        for f in self.errors:
            if isinstance(f, FileErrors):  # read by lorisnb.core.lifelong.scoring.recorded_thresholds
                f.thresholds = dict(thresholds)

    @property
    def conventions(self) -> str:
        """What was used, in words (the command line's ``conventions:`` line)."""
        return self.describe()

    def describe(self, swept: str | None = None) -> str:
        """:attr:`conventions`, with a sweep's grid in words (``swept``) for the spec's thresholds."""
        moved = "OpenLORIS: ground truth moved to each file's sensor frame; " if self.kind == "openloris" else ""
        return moved + self.spec.describe(swept)

    @property
    def thresholds(self) -> dict[str, Any]:
        """The default thresholds of the tables (the spec's)."""
        return {k: getattr(self.spec, k) for k in ("eps", "phi", "delta", "tau")}

    def sequences(
        self, eps: Eps | None = None, phi: float | None = None, delta: float | None = None, tau: float | None = None,
        **kw: Any,
    ) -> pd.DataFrame:  # fmt: skip
        """Per-sequence table at one setting (see :func:`lorisnb.core.lifelong.scoring.score`); thresholds and
        the RPE step not given are the spec's. A ``spec`` column holds the spec's exact text."""
        import pandas as pd

        s = self.spec
        kw = self._rpe(kw)
        rows = self.sequence_rows(eps, phi, delta, tau, **kw)
        stats = [] if rows and not any(c in rows[0] for c in STAT_COLUMNS) else STAT_COLUMNS  # let go: none kept
        table = pd.DataFrame(rows, columns=SEQUENCE_COLUMNS + EXTRA_COLUMNS + stats + ["spec"])
        if s.relation is not None and len(table):  # evo's -r: statistics of that pose relation
            from lorisnb.core.metrics.relation_table import relation_columns

            rpe = {k: v for k, v in kw.items() if k.startswith("rpe_")}
            rel = relation_columns(self.errors, s.relation, s.change_unit, **rpe)
            spec = table.pop("spec")
            table = pd.concat([table, rel.set_index(table.index)], axis=1)
            table["spec"] = spec
        if s.preset_name == "tartanair" and len(table):  # tartanair_tools' numbers
            spec = table.pop("spec")
            table = pd.concat([table, self.tartanair().set_index(table.index)], axis=1)
            table["spec"] = spec
        if s.preset_name == "kitti" and len(table):  # the KITTI devkit's metric
            from lorisnb.core.metrics.kitti_table import kitti_columns

            spec = table.pop("spec")
            table = pd.concat([table, kitti_columns(self.errors, s.kitti_precision).set_index(table.index)], axis=1)
            table["spec"] = spec
        return table

    def tartanair(self) -> pd.DataFrame:
        """tartanair_tools' numbers of every sequence (:func:`lorisnb.core.metrics.tartanair.tartanair_scores`),
        one row each in the order of :meth:`sequences`, with the spec's scale and seed."""
        import pandas as pd

        from lorisnb.core.lifelong.scoring import as_files
        from lorisnb.core.metrics.tartanair import TARTANAIR_COLUMNS, tartanair_scores

        rows = []
        for f in as_files(self.errors):
            for e in f.sequences:
                if e.matched < 2 or e.gt_quaternions is None or e.est_quaternions is None:
                    rows.append(dict.fromkeys(TARTANAIR_COLUMNS, float("nan")))
                    continue
                r = e.read_poses  # as read: tartanair_tools' input (lorisnb's alignment is not its)
                poses = (
                    (r[:, :3], r[:, 3:7], r[:, 7:10], r[:, 10:])
                    if r is not None
                    else (e.gt_positions, e.gt_quaternions, e.est_positions, e.est_quaternions)
                )
                rows.append(tartanair_scores(*poses, self.spec.tartanair_scale, self.spec.tartanair_seed))
        return pd.DataFrame(rows, columns=TARTANAIR_COLUMNS)

    def kitti_lengths(self) -> pd.DataFrame:
        """The KITTI devkit's per-length errors of every sequence and of every algorithm over all its
        sequences (:func:`lorisnb.core.metrics.kitti_table.kitti_lengths`), in the spec's precision."""
        from lorisnb.core.metrics.kitti_table import kitti_lengths

        return kitti_lengths(self.errors, self.spec.kitti_precision)

    def kitti_totals(self) -> pd.DataFrame:
        """The KITTI leaderboard's numbers per algorithm: the devkit's summary over every segment of
        all its sequences (:func:`lorisnb.core.metrics.kitti_table.kitti_totals`)."""
        from lorisnb.core.metrics.kitti_table import kitti_totals

        return kitti_totals(self.errors, self.spec.kitti_precision)

    def sequence_rows(
        self, eps: Eps | None = None, phi: float | None = None, delta: float | None = None, tau: float | None = None,
        **kw: Any,
    ) -> list[dict[str, Any]]:  # fmt: skip
        """:meth:`sequences` as rows (dicts), without pandas and without evo's ``relation`` columns.
        Where the poses were let go (``evaluate(..., statistics=False, keep_poses=False)``), the rows
        at the spec's setting are those without the statistics unless ``stats=True`` is asked for
        (then an EvaluationError: the statistics need the poses)."""
        s = self.spec
        kw = self._rpe(kw)
        setting = (s.eps if eps is None else eps, s.phi if phi is None else phi, s.delta if delta is None else delta,
                   s.tau if tau is None else tau)  # fmt: skip
        with threads(default_jobs()):  # a long sequence's statistics side by side (lorisnb.core.trajectory.blocks)
            try:
                rows = score_rows(self.errors, *setting, **kw)
            except EvaluationError:
                if not self.poses_let_go() or ("stats" in kw and not kw["stats"]):
                    raise
                if "stats" not in kw:
                    rows = score_rows(self.errors, *setting, **{**kw, "stats": False})  # at another setting: raises
                else:
                    raise EvaluationError(
                        "the statistics columns (stats=True) need each pose's errors, let go by evaluate(..., "
                        "statistics=False, keep_poses=False); sequences() at the spec's setting gives the table "
                        "without them, evaluate(..., statistics=True, keep_poses=False) one with them"
                    ) from None
        changed = {k: v for k, v in kw.items() if k in s.rpe_options() and v != getattr(s, k)}
        spec = (make_spec(s, **changed) if changed else s).canonical(thresholds=False)  # the RPE asked for
        for row in rows:
            row["spec"] = spec
        return rows

    def poses_let_go(self) -> bool:
        """Whether the per-pose errors were let go (``evaluate(..., keep_poses=False)``): only the
        spec's setting can be scored."""
        return any(isinstance(e, ScoresOnly) for f in self.errors for e in f.sequences)

    def _rpe(self, kw: dict[str, Any]) -> dict[str, Any]:
        """The RPE settings of a table: the spec's, with those given checked and normalized by the
        spec's own rules (:func:`lorisnb.core.spec.evalspec.make_spec`), so a value is read as in
        ``evaluate(..., rpe_unit=...)`` and on the command line (``rpe_unit='d'`` is degrees) and
        refused with the same message."""
        have = self.spec.rpe_options()
        given = {k: kw[k] for k in have if k in kw and not _same(kw[k], have[k])}  # the spec's own: checked
        checked = make_spec(self.spec, **given).rpe_options() if given else have
        return {**kw, **checked}

    def poses(self, eps: Eps | None = None, phi: float | None = None, **kw: Any) -> pd.DataFrame:
        """Per-pose table (see :func:`lorisnb.core.lifelong.scoring.pose_table`); a keyword other than
        the thresholds is refused, naming them."""
        known_keys(kw, ("eps", "phi"), "a setting of the pose table")
        return pose_table(self.errors, self.spec.eps if eps is None else eps, self.spec.phi if phi is None else phi)

    def scenes(
        self, eps: Eps | None = None, phi: float | None = None, delta: float | None = None, tau: float | None = None,
        **kw: Any,
    ) -> pd.DataFrame:  # fmt: skip
        """Per algorithm and scene, as in the paper's figures (see
        :func:`lorisnb.core.lifelong.aggregate.aggregate_scenes`); a keyword other than the
        thresholds is refused, naming them (the scene values read no RPE)."""
        known_keys(kw, THRESHOLD_NAMES, "a setting of the scene table")
        # the scene values read no statistics: without them (the same numbers), as a lean evaluation keeps them
        return aggregate_scenes(self.sequences(eps, phi, delta, tau, stats=False), self.durations())

    def relative(self, fractions: tuple[float, ...] | None = None, lengths: list[float] | None = None) -> pd.DataFrame:
        """rpg_trajectory_evaluation's relative error per sequence and sub-trajectory length: fractions
        of the whole ground truth's length (default rpg's 0.1 to 0.5), or rpg's preset ``lengths`` in
        metres (see :func:`lorisnb.core.metrics.relative.relative_table`); both at once is a
        ValidationError (the lengths were used, the fractions ignored)."""
        from lorisnb.core.metrics.relative import relative_table

        if fractions is not None and lengths is not None:
            raise ValidationError(
                "relative: fractions and lengths both given; expected one: fractions of the ground truth's length, "
                "or lengths in metres"
            )
        if fractions is None:
            fractions = RPG_FRACTIONS

        return relative_table(self.errors, fractions, lengths)

    def rpg_absolute(self) -> pd.DataFrame:
        """rpg_trajectory_evaluation's absolute errors and its scale error per sequence
        (:func:`lorisnb.core.metrics.relative.rpg_absolute_table`)."""
        from lorisnb.core.metrics.relative import rpg_absolute_table

        return rpg_absolute_table(self.errors)

    @property
    def algorithms(self) -> list[str]:
        return sorted({f.algorithm for f in self.errors})

    def durations(self) -> pd.DataFrame:
        """Ground-truth durations of every sequence of the scenes evaluated, seconds
        (:func:`lorisnb.core.lifelong.aggregate.spans_table` of :meth:`spans`)."""
        return spans_table(self.spans())

    def spans(self) -> dict[str, dict[int, tuple[float, float]]]:
        """First and last ground-truth stamp (seconds) of every sequence of the scenes evaluated:
        scene -> sequence -> span. A pair's or a manifest's scene has the spans of its own ground
        truth as read while evaluating (none where no input of it was evaluated), never the data
        root's scene of the same name; an OpenLORIS scene's come from the data root if needed."""
        known: dict[str, dict[int, tuple[float, float]]] = {}
        for f in self.errors:
            if f.groundtruth_spans:
                known.setdefault(f.scene, {}).update(f.groundtruth_spans)
        scenes = list(dict.fromkeys(f.scene for f in self.errors))
        if set(known) == set(scenes) or self.kind != "openloris":  # no ground truth read again
            return {s: dict(sorted(known.get(s, {}).items())) for s in scenes}
        return scene_spans(sorted(scenes, key=SCENES.index), self.data)

    @property
    def warnings(self) -> list[str]:
        """Every note: the spec's on the options (:attr:`notes`: ``lifelong`` on a pair, ...), then
        each input's (``FileErrors.warnings``: its reader's and its ground truth's, the checks')."""
        return [*self.notes, *(w for f in self.errors for w in f.warnings)]

    @property
    def unscored(self) -> list[Failure]:
        """Inputs read but not scored (no pose matched; manifest sessions without an estimate),
        each with a one-line reason: see :func:`lorisnb.tools.evaluation.status.unscored`."""
        return unscored(self)

    def exit_status(self) -> int:
        """0 if every input was read and matched the ground truth, else 1: every command's exit
        status (:mod:`lorisnb.tools.evaluation.status`)."""
        return exit_status(self)

    def failures_table(self) -> pd.DataFrame:
        """Failed, skipped and unscored inputs (:attr:`unscored`) with the reason, one row each."""
        unscored = self.unscored
        rows = [dict(file=str(f.path), status="failed", kind=f.kind, error=f.error) for f in self.failures]
        rows += [
            dict(file=str(f.path), status="skipped", kind=f.kind, error=f.error) for f in skipped_only(self, unscored)
        ]
        rows += [dict(file=str(f.path), status="not scored", kind=f.kind, error=f.error) for f in unscored]
        import pandas as pd

        return pd.DataFrame(rows, columns=["file", "status", "kind", "error"])

    def __repr__(self) -> str:
        def count(n: int, word: str) -> str:
            return f"{n} {word}{'' if n == 1 else 's'}"

        scenes = len({f.scene for f in self.errors})
        parts = [f"{count(len(self.errors), 'input')} ({count(len(self.algorithms), 'algorithm')}, "
                 f"{count(scenes, 'scene')})"]  # fmt: skip
        unscored = self.unscored
        parts += [f"{n} {w}" for n, w in ((len(self.failures), "failed"), (len(unscored), "unscored"),
                                          (len(skipped_only(self, unscored)), "skipped")) if n]  # fmt: skip
        if any(isinstance(e, ScoresOnly) for f in self.errors for e in f.sequences):
            parts.append("scores at its setting only, poses let go (keep_poses=False)")
        return f"<Evaluation: {', '.join(parts)}; {self.spec!r}>"
