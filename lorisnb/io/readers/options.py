"""Which reading options apply to which trajectory format, checked in one place for every surface
(the command line, Python's ``evaluate_pairs`` / ``read_bag``, a manifest): times files only for
KITTI, topics and TF chains only for bags, and a topic or a TF chain, not both."""

from __future__ import annotations

from collections.abc import Callable, Mapping

from lorisnb.errors import ValidationError

NEEDS = {"est_times": "kitti", "gt_times": "kitti", "topic": "bag", "tf": "bag", "gt_topic": "bag", "gt_tf": "bag"}


def check_reading(
    values: Mapping[str, object], fmt: str = "bag", gt_fmt: str = "bag", name: Callable[[str], str] = str
) -> None:
    """Refuse a reading option (``values``: keys of :data:`NEEDS`, None when not given) that cannot
    apply: one for another format than its side's (``fmt`` for the estimates, ``gt_fmt`` for the
    ground truth), or a topic and a TF chain for the same side. ``name(key)`` is how the user's
    surface spells the option (``--gt-topic``, ``groundtruth_topic``)."""
    for key, value in values.items():
        gt = key.startswith("gt_")
        has, needs = (gt_fmt if gt else fmt), NEEDS[key]
        if value is not None and has != needs:
            side = "the ground truth is" if gt else "the estimates are"
            raise ValidationError(f"{name(key)}: only for {needs} files; {side} read as {has}")
    for pre in ("", "gt_"):
        if values.get(pre + "topic") is not None and values.get(pre + "tf") is not None:
            raise ValidationError(
                f"{name(pre + 'topic')} and {name(pre + 'tf')} both given: give {name(pre + 'topic')} (a topic of "
                f"poses) or {name(pre + 'tf')} (a TF chain parent:child), not both"
            )
