"""What a figure draws, as data: its texts and its numbers, independent of the renderer.

:func:`figure_data` walks a Matplotlib figure's artists in their order and records, for
each, what it shows in *data* coordinates — a line's points, a collection's offsets, paths
and colour values, a patch's outline, an image's array and extent, a text's string and its
place in data coordinates — and how it is styled (colours, widths, sizes, the axes' scales,
their cells of the grid and the limits set by hand). Ticks, tick labels, spines,
autoscaled limits and the places the layout gives (axes, titles, legends, axis labels) are
left out: they follow from the data and the layout (on a log scale, a value at rounding
level can move a decade of ticks, and with it every title). Two figures whose data agree
to rounding draw the same picture to the eye; the pixels of their PNG files may still
differ (anti-aliasing), which is why ``nonholo reproduce`` compares this record
(:mod:`nonholo.io.numeric_diff`) rather than the files to decide whether to redraw.

The record is ``(words, numbers)``: ``words`` a list of strings (the artists' kinds, their
texts, the shapes of their arrays), ``numbers`` one float array. :func:`to_bytes` and
:func:`from_bytes` store it (LZMA-compressed, no time stamp: the same record gives the same
bytes).
"""
from __future__ import annotations

import json
import lzma
import struct

import numpy as np
from matplotlib import axis as mpl_axis
from matplotlib import collections as mpl_collections
from matplotlib import colors as mpl_colors
from matplotlib import image as mpl_image
from matplotlib import lines as mpl_lines
from matplotlib import patches as mpl_patches
from matplotlib import spines as mpl_spines
from matplotlib import text as mpl_text
from matplotlib.axes import Axes
from matplotlib.figure import Figure

__all__ = ["figure_data", "parts", "to_bytes", "from_bytes", "FORMAT"]

#: The tag of a stored record.
FORMAT = "nonholo.figure_data/2"
_MAGIC = b"NHFD1\n"


class _Record:
    def __init__(self):
        self.words: list[str] = []
        self.chunks: list[np.ndarray] = []

    def add(self, kind: str, *arrays, text: str | None = None) -> None:
        shapes = []
        for a in arrays:
            a = np.ma.filled(np.ma.asarray(a, dtype=float), np.nan) if a is not None else np.zeros(0)
            self.chunks.append(np.ravel(a))
            shapes.append("x".join(map(str, np.shape(a))))
        self.words.append(f"{kind}[{','.join(shapes)}]" + ("" if text is None else f":{text}"))

    def result(self) -> tuple[list[str], np.ndarray]:
        numbers = np.concatenate(self.chunks) if self.chunks else np.zeros(0)
        return self.words, numbers


def _rgba(c) -> np.ndarray:
    try:
        return np.asarray(mpl_colors.to_rgba_array(c), dtype=float)
    except (ValueError, TypeError):
        return np.zeros((0, 4))


def _axis_parts(fig: Figure) -> tuple[set[int], set[int]]:
    """The artists of the axes' axis objects (ticks, tick labels, offset texts) and the
    spines, left out; the axis labels, whose place the layout sets from the tick labels."""
    skipped, labels = set(), set()
    for artist in fig.findobj(lambda a: isinstance(a, (mpl_axis.Axis, mpl_spines.Spine))):
        label = getattr(artist, "label", None)
        labels.add(id(label))
        skipped.update(id(a) for a in artist.findobj() if a is not label)
    return skipped, labels


def _axes(rec: _Record, ax: Axes) -> None:
    # limits set by hand; autoscaled ones follow from the data (on a log scale, a value at
    # rounding level, 1e-14 or 1.0004e-14, moves them by its own relative change)
    names = ("x", "y", "z") if hasattr(ax, "get_zlim") else ("x", "y")
    limits = [getattr(ax, f"get_{n}lim")() if not getattr(ax, f"get_autoscale{n}_on")() else (np.nan, np.nan)
              for n in names]
    scales = [getattr(ax, f"get_{n}scale")() for n in names]
    if len(names) == 3:                             # 3-D axes: the view
        limits.append((getattr(ax, "elev", 0.0), getattr(ax, "azim", 0.0)))
    spec = ax.get_subplotspec()         # its cell in the grid; a layout engine sets the place
    place = spec.get_geometry() if spec is not None else ax.get_position(original=True).bounds
    rec.add("axes", np.asarray(place, dtype=float), np.array(limits, dtype=float),
            text=",".join(scales) + f":{ax.name}")


def _line(rec: _Record, line: mpl_lines.Line2D) -> None:
    data = line.get_data_3d() if hasattr(line, "get_data_3d") else line.get_xydata().T
    rec.add("line", np.array(data, dtype=float), _rgba(line.get_color()),
            [line.get_linewidth(), line.get_markersize(), line.get_alpha() or 1.0],
            text=f"{line.get_linestyle()}:{line.get_marker()}:{line.get_label()}")


def _flat(x) -> np.ndarray:
    """Numbers of an array or of a ragged list of arrays, flattened."""
    try:
        return np.ravel(np.asarray(x, dtype=float))
    except (ValueError, TypeError):
        parts = [_flat(v) for v in x]
        return np.concatenate(parts) if parts else np.zeros(0)


def _collection(rec: _Record, coll: mpl_collections.Collection) -> None:
    # a 3-D collection's own data (its 2-D paths are a projection made when drawn)
    three_d = [_flat(x) for x in (getattr(coll, name, None) for name in ("_vec", "_segments3d", "_offsets3d"))
               if x is not None]
    if three_d:
        vertices = np.concatenate(three_d)
    else:
        paths = [np.ravel(p.vertices) for p in coll.get_paths()]
        vertices = np.concatenate(paths) if paths else np.zeros(0)
    values = coll.get_array()
    rec.add("collection", vertices, np.asarray(coll.get_offsets(), dtype=float),
            np.zeros(0) if values is None else values, _rgba(coll.get_facecolor()),
            _rgba(coll.get_edgecolor()), np.atleast_1d(coll.get_linewidth()),
            text=f"{type(coll).__name__}:{coll.get_label()}")


def _patch(rec: _Record, patch: mpl_patches.Patch) -> None:
    segment = getattr(patch, "_segment3d", None)
    if segment is not None:
        outline = np.asarray(segment, dtype=float)
    else:
        outline = patch.get_patch_transform().transform(patch.get_path().vertices)
    rec.add("patch", outline, _rgba(patch.get_facecolor()), _rgba(patch.get_edgecolor()),
            [patch.get_linewidth()], text=type(patch).__name__)


def _image(rec: _Record, image: mpl_image.AxesImage) -> None:
    norm = image.norm
    rec.add("image", image.get_array(), image.get_extent(),
            [np.nan if norm.vmin is None else norm.vmin, np.nan if norm.vmax is None else norm.vmax],
            text=image.get_cmap().name)


def _text(rec: _Record, text: mpl_text.Text, placed_by_layout: bool) -> None:
    if not text.get_text():
        return
    # a place in data coordinates is data; any other (titles, legends, axis labels) the
    # layout may move when the figure is drawn
    in_data = text.axes is not None and text.get_transform() == text.axes.transData
    where = text.get_position() if in_data and not placed_by_layout else (np.nan, np.nan)
    rec.add("text", np.asarray(where, dtype=float), _rgba(text.get_color()),
            [text.get_fontsize(), text.get_rotation()], text=text.get_text())


def figure_data(fig: Figure) -> tuple[list[str], np.ndarray]:
    """The texts and numbers a figure draws (see the module).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.

    Returns
    -------
    words : list of str
        Every artist's kind, the shapes of its arrays and its text.
    numbers : numpy.ndarray
        Every artist's numbers, in the order of ``words``.
    """
    rec = _Record()
    rec.add("figure", fig.get_size_inches(), [fig.dpi])
    skipped, axis_labels = _axis_parts(fig)
    for artist in fig.findobj(include_self=False):
        if id(artist) in skipped or not artist.get_visible():
            continue
        if isinstance(artist, Axes):
            _axes(rec, artist)
        elif isinstance(artist, mpl_lines.Line2D):
            _line(rec, artist)
        elif isinstance(artist, mpl_collections.Collection):
            _collection(rec, artist)
        elif isinstance(artist, mpl_patches.Patch):
            _patch(rec, artist)
        elif isinstance(artist, mpl_image.AxesImage):
            _image(rec, artist)
        elif isinstance(artist, mpl_text.Text):
            _text(rec, artist, id(artist) in axis_labels)
    return rec.result()


def parts(words: list[str], numbers) -> list[tuple[str, np.ndarray]]:
    """Each artist's word with its numbers.

    Parameters
    ----------
    words, numbers
        A record of :func:`figure_data`.

    Returns
    -------
    list of (str, numpy.ndarray)
        In the record's order; ``[]`` where the numbers do not fit the words.
    """
    numbers = np.asarray(numbers)
    out, at = [], 0
    for word in words:
        if "[" not in word or "]" not in word:
            return []
        shapes = word[word.index("[") + 1:word.index("]")].split(",")
        try:
            size = sum(int(np.prod([int(d) for d in s.split("x")])) if s else 1 for s in shapes)
        except ValueError:
            return []
        out.append((word, numbers[at:at + size]))
        at += size
    return out if at == numbers.size else []


def to_bytes(words: list[str], numbers) -> bytes:
    """A record as bytes: the same record, the same bytes.

    Parameters
    ----------
    words : list of str
        The record's texts.
    numbers : array_like
        Its numbers.

    Returns
    -------
    bytes
        Compressed.
    """
    head = json.dumps({"format": FORMAT, "words": list(words)}, ensure_ascii=True).encode()
    body = np.ascontiguousarray(numbers, dtype="<f8").tobytes()
    return _MAGIC + lzma.compress(struct.pack("<Q", len(head)) + head + body, preset=9)


def from_bytes(data: bytes) -> tuple[list[str], np.ndarray]:
    """Inverse of :func:`to_bytes`.

    Parameters
    ----------
    data : bytes
        A stored record.

    Returns
    -------
    words : list of str
        The texts.
    numbers : numpy.ndarray
        The numbers.

    Raises
    ------
    ValueError
        For bytes that are not such a record.
    """
    if not data.startswith(_MAGIC):
        raise ValueError("not a figure record")
    try:
        raw = lzma.decompress(data[len(_MAGIC):])
        (n,) = struct.unpack("<Q", raw[:8])
        head = json.loads(raw[8:8 + n].decode())
        body = raw[8 + n:]
    except (lzma.LZMAError, struct.error, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"damaged figure record: {exc}") from None
    if not isinstance(head, dict) or head.get("format") != FORMAT or not isinstance(head.get("words"), list) \
            or not all(isinstance(w, str) for w in head["words"]) or len(body) % 8:
        raise ValueError("damaged figure record")
    return head["words"], np.frombuffer(body, dtype="<f8").copy()
