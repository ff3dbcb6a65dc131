"""The threshold explorer's PNG redrawn from the first changing artist on (BlitCanvas) is the image a
full ``savefig(bbox_inches="tight")`` of the same figure gives, pixel for pixel: after threshold
moves, a scene change, title changes (one that moves the layout, one wider than the axes), and
after the kept part of the figure is changed behind its back."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

import lorisnb as ln
from lorisnb.tools.figures.blit import BlitCanvas, encode_png
from lorisnb.tools.figures.plotting import Timeline, plot_timeline
from lorisnb.tools.notebook.start import figure_png
from lorisnb.tools.notebook.widgets import ThresholdExplorer

ALGOS = ["maslam", "vins_mono_color_imu_with_loop", "ds-slam"]


@pytest.fixture(scope="module")
def ev(icra20):
    return ln.evaluate(icra20 / "lifelong", algorithms=ALGOS, scenes=["home", "corridor"], progress=False)


def pixels(png: bytes) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGBA"))


def full_savefig(fig, dpi: int = 150) -> np.ndarray:
    """matplotlib's own rendering: everything drawn, tight bounding box."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    return pixels(buf.getvalue())


def same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and bool((a == b).all())


def test_a_threshold_move_blitted_equals_a_full_savefig(ev):
    """The fast loop's check of the test below (thorough): one slider move, redrawn from the first
    changing artist, is the PNG a full savefig of the same figure gives, pixel for pixel."""
    ex = ThresholdExplorer(ev.errors, ev.durations(), "paper", 30.0, 1.0, 60.0, scene="home")
    _, fig = ex.results()
    figure_png(fig)
    blits = fig.canvas.blits
    ex.phi = 2.0
    _, fig = ex.results()
    fast = pixels(figure_png(fig))
    assert isinstance(fig.canvas, BlitCanvas) and fig.canvas.blits == blits + 1
    assert same(fast, full_savefig(fig))


@pytest.mark.thorough  # 8 moves, each PNG against a twin's full savefig (4 s of CPU)
def test_slider_changes_blitted_equal_a_full_savefig_pixel_for_pixel(ev):
    """One explorer redrawn through threshold moves and a scene change (every PNG after the first of
    a scene blitted), each PNG compared with a full savefig of a twin explorer's figure at the same
    values, and, at the end, of the same figure."""
    ex = ThresholdExplorer(ev.errors, ev.durations(), "paper", 30.0, 1.0, 60.0, scene="home")
    twin = ThresholdExplorer(ev.errors, ev.durations(), "paper", 30.0, 1.0, 60.0, scene="home")
    steps = [(None, None), ("phi", 2.0), ("eps", 0.1), ("delta", 5.0), ("scene", "corridor"), ("phi", 90.0),
             ("scene", "home"), ("eps", 3.0)]  # fmt: skip
    blits = 0
    for name, value in steps:
        if name is not None:
            setattr(ex, name, value)
            setattr(twin, name, value)
        _, fig = ex.results()
        fast = pixels(figure_png(fig))
        assert isinstance(fig.canvas, BlitCanvas)
        if name not in (None, "scene"):
            assert fig.canvas.blits == blits + 1, (name, value)  # redrawn from the first changing artist
        blits = fig.canvas.blits
        assert same(fast, full_savefig(twin.results()[1])), (name, value)
    assert same(fast, full_savefig(fig))


@pytest.mark.thorough  # 8 titles, each PNG against a twin's full savefig (4 s of CPU)
def test_title_changes_that_move_the_layout_or_the_bounding_box(ev):
    """A title of two lines (laid out again: the axes move) and one wider than the axes (the tight
    bounding box grows): the background is drawn again, and the PNG is savefig's."""
    files = [f for f in ev.errors if f.scene == "home"]
    durations = ev.durations()[ev.durations()["scene"] == "home"]
    table = ev.scenes(1.0, 30.0, 1.0, 60.0)
    table = table[table["scene"] == "home"]
    ours, twin = Timeline(files, durations), Timeline(files, durations)
    titles = [
        "short",
        "shorter",
        "two\nlines",
        "two\nlines again",
        "wide " * 60,
        "wide " * 61,
        "short",
        None,
    ]  # 61: wider still
    for title in titles:
        fig = ours.draw(table, 1.0, 30.0, 1.0, title)
        captures = fig.canvas.captures
        fast = pixels(figure_png(fig))
        assert same(fast, full_savefig(twin.draw(table, 1.0, 30.0, 1.0, title))), title
        if title in ("shorter", "two\nlines again"):  # the same layout and box as before: blitted
            assert fig.canvas.captures == captures, title
    assert same(fast, full_savefig(fig))


def test_a_change_to_the_kept_part_is_drawn(ev):
    """Row names, the axis label or the limits changed by the caller after a PNG, or the figure drawn
    by the caller (which marks everything drawn): the next PNG draws everything again, as savefig."""
    ex = ThresholdExplorer(ev.errors, ev.durations(), 3.0, scene="home")
    _, fig = ex.results()
    figure_png(fig)
    ax = fig.axes[0]
    changes = [
        lambda: ax.set_yticks(ax.get_yticks(), [f"row {k}" for k in range(len(ax.get_yticks()))]),
        lambda: ax.set_xlabel("seconds"),
        lambda: ax.set_xlim(*(v * 1.1 for v in ax.get_xlim())),
        lambda: ax.yaxis.label.set_color("red") or ax.set_ylabel("algorithms"),
        lambda: fig.axes[0].xaxis.label.set_text("drawn by the caller") or full_savefig(fig),
    ]
    for k, change in enumerate(changes):
        ex.phi = 10.0 + k
        _, fig = ex.results()
        change()
        captures = fig.canvas.captures
        fast = pixels(figure_png(fig))
        assert fig.canvas.captures == captures + 1, k
        assert same(fast, full_savefig(fig)), k


def test_the_legend_drawn_before_the_axes_looks_the_same(ev):
    """The timeline's legend is drawn before the axes (kept with the background); at matplotlib's
    own place in the order (after the axes) the figure is the same, pixel for pixel."""
    files = [f for f in ev.errors if f.scene == "corridor"]
    durations = ev.durations()[ev.durations()["scene"] == "corridor"]
    table = ev.scenes(3.0, 30.0, 1.0, 60.0)
    fig = plot_timeline(files, durations, table[table["scene"] == "corridor"], 3.0, 30.0, title="corridor")
    (legend,) = fig.legends
    before = full_savefig(fig)
    legend.set_zorder(5)  # matplotlib's default for a legend
    assert same(before, full_savefig(fig))


def test_encode_png_round_trips():
    rng = np.random.default_rng(0)
    image = rng.integers(0, 256, (37, 53, 4), dtype=np.uint8)
    image[10:20] = image[9]  # rows alike, as a plot's
    for level in (0, 1, 9):
        assert same(pixels(encode_png(image, level)), image)
