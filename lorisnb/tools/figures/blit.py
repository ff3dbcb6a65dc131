"""A figure's PNG rendered again after a change by redrawing only what changed (blitting), the same
image as ``savefig(format="png", bbox_inches="tight")`` pixel for pixel.

:class:`BlitCanvas` is the Agg canvas of a figure some of whose artists change between renderings
(a :class:`~lorisnb.tools.figures.plotting.Timeline`'s segments, texts and title): everything drawn
before the first changing artist, in matplotlib's own draw order, is drawn once and kept as a
pixel buffer; each later PNG restores it and draws only the artists from the first changing one
onwards, in the same order. Public matplotlib API only: the tight bounding box is computed as
``savefig`` computes it and passed to ``savefig``, which lays the figure out for it and calls this
canvas's ``print_png``.
"""

from __future__ import annotations

import io
import struct
import zlib
from collections.abc import Callable, Sequence
from operator import attrgetter
from typing import Any

import matplotlib as mpl
import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg, RendererAgg
from matplotlib.figure import Figure
from matplotlib.image import AxesImage
from matplotlib.layout_engine import PlaceHolderLayoutEngine
from matplotlib.transforms import Bbox

#: What a figure's PNG for the notebook is encoded with outside :class:`BlitCanvas`: Pillow at zlib
#: level 1 instead of 6. The PNG only travels to the local browser (or is made compact for a
#: report); icra20's market timeline: 67 instead of 113 ms, 154 instead of 136 kB (under load 3).
FAST_PNG = {"compress_level": 1}

#: rcParams that Agg reads while drawing (not when an artist is made): a background drawn under
#: other values is drawn again.
_DRAW_RC: tuple[Any, ...] = ("text.hinting", "text.hinting_factor", "text.kerning_factor", "path.simplify",
            "path.simplify_threshold", "path.snap", "agg.path.chunksize")  # fmt: skip


class BlitCanvas(FigureCanvasAgg):
    """The Agg canvas of a figure whose ``changing()`` artists (children of one axes) change between
    renderings; :meth:`png` renders it to PNG redrawing only from the first changing artist onwards.

    The kept part (the background) is drawn again whenever it may differ: another size, resolution
    or bounding box, the axes moved or their limits changed, an artist of it added, removed or
    changed (matplotlib marks a changed artist stale), or the figure drawn by anything else than
    this canvas (a ``savefig`` of the caller's). Figures it cannot blit (images, child axes, a
    layout engine, rasterized artists) are rendered by ``savefig`` as they are. Renderers are kept
    one per size and resolution (the measuring one and the tight one), so that the texts' sizes are
    measured once (matplotlib keeps them per renderer)."""

    def __init__(self, figure: Figure, changing: Callable[[], Sequence[Artist]]) -> None:
        super().__init__(figure)
        self._changing = changing
        self._renderers: dict[tuple[int, int, float], RendererAgg] = {}
        self._background: tuple[tuple[Any, ...], Any, list[Artist]] | None = None
        self._armed = False  # inside png(): print_png blits
        self._draws = 0  # the figure's draws (draw_event), anyone's
        self._own_draws = 0  # ... when png() last finished
        #: how many backgrounds were drawn (a full draw each) and how many PNGs blitted (for tests)
        self.captures = self.blits = 0
        self.mpl_connect("draw_event", self._drawn)

    def _drawn(self, _event: Any) -> None:
        self._draws += 1

    def get_renderer(self) -> RendererAgg:
        """The renderer of the figure's current size and resolution: one kept per (width, height,
        dpi), at most four."""
        w, h = self.get_width_height(physical=True)
        key = (w, h, float(self.figure.dpi))
        renderer = self._renderers.get(key)
        if renderer is None:
            if len(self._renderers) >= 4:
                self._renderers.clear()
            renderer = self._renderers[key] = RendererAgg(w, h, self.figure.dpi)
        self.renderer = renderer
        return renderer

    def png(self, dpi: float = 150, pil_kwargs: dict[str, Any] | None = None) -> bytes:
        """The figure as ``savefig(buf, format="png", dpi=dpi, bbox_inches="tight",
        pil_kwargs=pil_kwargs)`` renders it, pixel for pixel, redrawing only what changed since the
        last call where it can."""
        fig = self.figure
        engine = fig.get_layout_engine()
        if engine is not None and not isinstance(engine, PlaceHolderLayoutEngine):
            return _savefig(fig, dpi, "tight", pil_kwargs)  # laid out again at each draw: not blitted
        was = fig.dpi
        buf = io.BytesIO()
        try:
            if self._draws != self._own_draws or not self._unchanged():
                self._background = None  # checked before the draws below mark everything drawn
            fig.set_dpi(dpi)
            # the tight bounding box as savefig measures it; savefig's draw without rendering first is
            # left out (nothing here is placed at draw time but what get_tightbbox places itself)
            bbox = fig.get_tightbbox(self.get_renderer()).padded(mpl.rcParams["savefig.pad_inches"])
            fig.set_layout_engine(None)  # the placeholder would make savefig draw without rendering
            self._armed = True
            fig.savefig(buf, format="png", dpi=dpi, bbox_inches=bbox, pil_kwargs=pil_kwargs)
        finally:
            self._armed = False
            if engine is not None:
                fig.set_layout_engine(engine)
            fig.set_dpi(was)
        if self._background is not None:
            for artist in self._background[2]:  # drawn, or checked unchanged: not stale
                artist.stale = False
        self._own_draws = self._draws
        return buf.getvalue()

    def _unchanged(self) -> bool:
        """Whether no artist of the kept background was changed, added or removed since."""
        if self._background is None or (order := draw_order(self.figure, self._changing())) is None:
            return False
        kept = self._background[2]
        now = _descendants(order[0])
        return len(now) == len(kept) and all(a is b and not a.stale for a, b in zip(now, kept, strict=True))

    def print_png(self, filename_or_obj: Any, *, metadata: dict[str, str] | None = None,
                  pil_kwargs: dict[str, Any] | None = None, **_figure: Any) -> None:  # fmt: skip
        """As Agg's, blitting inside :meth:`png`. ``savefig`` passes a third party's print method the
        keywords other formats use (``dpi``, ``facecolor``, ``edgecolor``, ``orientation``,
        ``bbox_inches_restore``): Agg's PNG ignores them, and so does this."""
        if not self._armed:
            return super().print_png(filename_or_obj, metadata=metadata, pil_kwargs=pil_kwargs)
        self._render()
        level = (pil_kwargs or {}).get("compress_level", 6)
        filename_or_obj.write(encode_png(np.asarray(self.buffer_rgba()), level))

    def _render(self) -> None:
        """Draw the figure (savefig has laid it out in its bounding box): the background restored
        and the artists from the first changing one onwards drawn, or everything."""
        fig = self.figure
        renderer = self.get_renderer()
        order = draw_order(fig, self._changing())
        if order is None:
            self._background = None
            FigureCanvasAgg.draw(self)
            return
        (prefix, suffix), ax = order, _axes_of(self._changing())
        key = (
            renderer.width,
            renderer.height,
            float(fig.dpi),
            tuple(fig.bbox.bounds),
            tuple(fig.transFigure.transform((0.0, 0.0))),
            tuple(fig.get_size_inches()),
            tuple(ax.get_position().bounds) if ax is not None else None,
            tuple(ax.viewLim.bounds) if ax is not None else None,
            tuple(map(id, prefix)),
            id(renderer),
            tuple(mpl.rcParams[k] for k in _DRAW_RC),
        )
        if self._background is not None and self._background[0] == key:
            self.restore_region(self._background[1])
            self.blits += 1
        else:
            shown = [a.get_visible() for a in suffix]
            for a in suffix:
                a.set_visible(False)
            try:
                FigureCanvasAgg.draw(self)
                region = self.copy_from_bbox(Bbox.from_bounds(0, 0, renderer.width, renderer.height))
            finally:
                for a, v in zip(suffix, shown, strict=True):
                    a.set_visible(v)
            self._background = (key, region, _descendants(prefix))
            self.captures += 1
        for a in suffix:
            a.draw(renderer)


def encode_png(rgba: np.ndarray, level: int = 1) -> bytes:
    """An RGBA image (rows top to bottom, uint8) as PNG: each row filtered as "up" (its difference
    from the row above, vectorized: a plot's rows are mostly alike) and zlib at ``level``. No
    metadata. For icra20's market timeline at 150 dpi (1,492 x 1,184 px): 18-25 ms and 157 kB,
    where Pillow's encoder (adaptive filters) takes 70-90 ms at compress_level 1 (154 kB) and 110-140
    ms at its default 6 (136 kB), 2 cores under load 3."""
    h, w, _ = rgba.shape
    rows = rgba.reshape(h, w * 4)
    filtered = np.empty((h, w * 4 + 1), np.uint8)
    filtered[:, 0] = 2  # "up"
    filtered[0, 0] = 0  # the first row as it is
    filtered[0, 1:] = rows[0]
    np.subtract(rows[1:], rows[:-1], out=filtered[1:, 1:])  # modulo 256

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0)  # 8 bits, RGBA, deflate, filtered, no interlace
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(filtered.data, level))
        + chunk(b"IEND", b"")
    )


def _descendants(artists: Sequence[Artist]) -> list[Artist]:
    return [d for a in artists for d in a.findobj()]


def _axes_of(artists: Sequence[Artist]) -> Axes | None:
    axes = {id(a.axes): a.axes for a in artists}
    ax = next(iter(axes.values())) if len(axes) == 1 else None
    return ax if isinstance(ax, Axes) else None


def draw_order(fig: Figure, changing: Sequence[Artist]) -> tuple[list[Artist], list[Artist]] | None:
    """The figure's artists as matplotlib draws them (``Figure.draw``, then ``Axes.draw``: each
    level's children sorted by zorder, stable), split before the first of ``changing`` (artists of
    one axes): what is drawn before it, as drawn at the top level (the figure's patch, figure-level
    artists, the axes' patch and its children), and the artists from it onwards, each to be drawn
    alone. None where the figure is not drawn that simply: images, child axes, subfigures,
    rasterization by zorder, animated figure-level artists, or no changing artist."""
    ax = _axes_of(changing)
    if ax is None or ax.get_figure(root=False) is not fig or ax.name != "rectilinear" or fig.subfigs:
        return None
    if ax.child_axes or ax.get_rasterization_zorder() is not None:
        return None
    children = ax.get_children()
    if any(isinstance(a, AxesImage) for a in children) or any(a.get_animated() for a in fig.get_children()):
        return None
    children.remove(ax.patch)
    framed = ax.axison and ax.get_frame_on()
    if not framed:
        children = [a for a in children if a not in ax.spines.values()]
    if not ax.axison:
        children = [a for a in children if a is not ax.xaxis and a is not ax.yaxis]
    in_axes = ([ax.patch] if framed else []) + sorted(children, key=attrgetter("zorder"))  # saving: animated too
    ids = {id(a) for a in changing}
    first = next((k for k, a in enumerate(in_axes) if id(a) in ids), None)
    if first is None:
        return None
    top = sorted((a for a in fig.get_children() if a is not fig.patch), key=lambda a: a.get_zorder())
    at = next(k for k, a in enumerate(top) if a is ax)
    prefix = [fig.patch, *top[:at], *in_axes[:first]]
    return prefix, [*in_axes[first:], *top[at + 1 :]]


def _savefig(fig: Figure, dpi: float, bbox_inches: Any, pil_kwargs: dict[str, Any] | None) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches=bbox_inches, pil_kwargs=pil_kwargs)
    return buf.getvalue()
