"""The main job's outputs, each written only where it differs from the file already there.

``nonholo reproduce`` runs the same computations on every machine, but another CPU, BLAS or
kernel backend rounds differently: a terminal error of 1.96139e-11 rad becomes 1.96146e-11
and a figure's anti-aliased pixels move. :class:`Outputs` keeps the file already there
unless its content differs beyond the tolerances of :mod:`nonholo.io.numeric_diff`
(numbers within ``1e-9`` of their magnitude, or of 1 where smaller; all other text equal):

- texts (Markdown, CSV) are compared as they are;
- JSON objects (plan files, ``summary.json``) are compared without their ``"made_by"``
  record (:mod:`nonholo.io.provenance`): the file kept is the one made first, and says by
  what;
- a figure is redrawn (PNG and PDF) only when the data it plots moved
  (:func:`nonholo.viz.figure_data.figure_data`, stored beside it in
  ``figure_data/<stem>.data``); a figure of numbers known only to a coarser tolerance is
  given it (``rtol``: the physics executions' touch-ups, see
  :data:`nonholo.paper.reproduce.TOUCH_UP_RTOL`);
- any other file (the GIF) is remade when the numbers it is drawn from moved (stored the
  same way).

With ``check=True`` nothing is written: each output that differs beyond the tolerances, or
is missing, is listed with how far it is (:attr:`Outputs.differences`), for
``nonholo reproduce --check``.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..io import numeric_diff, safe_write
from ..viz import figure_data, style

__all__ = ["Outputs", "Difference", "DATA_DIR", "PROVENANCE_KEY"]

#: The folder, inside the output folder, of the data each figure and animation was drawn from.
DATA_DIR = "figure_data"
#: The key of a JSON output's record of what made it, left out of comparisons.
PROVENANCE_KEY = "made_by"


@dataclass(frozen=True)
class Difference:
    """An output whose new content differs from the file there.

    Parameters
    ----------
    path : pathlib.Path
        The file.
    distance : float
        The largest difference of its numbers in units of their scale
        (:func:`nonholo.io.numeric_diff.distance`); ``inf`` where the texts differ in more
        than numbers or the file is missing or unreadable.
    why : str
        In words.
    """

    path: Path
    distance: float
    why: str

    def __str__(self) -> str:
        return f"{self.path}: {self.why}"


def _read_text(path: Path) -> str | None:
    try:
        if not path.is_file():
            return None
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None


def _read_bytes(path: Path) -> bytes | None:
    try:
        return path.read_bytes() if path.is_file() else None
    except OSError:
        return None


def _without_provenance(value):
    return {k: v for k, v in value.items() if k != PROVENANCE_KEY} if isinstance(value, dict) else value


def _where(old, new, rtol: float) -> str:
    """``" (most in <the artist>)"``: the first artist of a drawing whose record moved most."""
    before, after = figure_data.parts(*old), figure_data.parts(*new)
    if not before or len(before) != len(after):
        return ""
    moved = [max(numeric_diff.text_distance(wa, wb), numeric_diff.array_distance(a, b))
             for (wa, a), (wb, b) in zip(before, after)]
    k = int(np.argmax(moved))
    return f" (most in {after[k][0][:80]!r})" if moved[k] > rtol else ""


class Outputs:
    """Writes the main job's outputs where they differ (see the module).

    Parameters
    ----------
    outdir : str or pathlib.Path
        The output folder.
    check : bool
        Write nothing; collect the differences.
    dpi : int
        The PNG figures' resolution.
    """

    def __init__(self, outdir, check: bool = False, dpi: int = 150):
        self.outdir = Path(outdir)
        self.check = bool(check)
        self.dpi = dpi
        #: Outputs whose content differs beyond the tolerances (or that are missing).
        self.differences: list[Difference] = []
        #: Files written (none with ``check``).
        self.written: list[Path] = []
        #: Files left as they were, their content agreeing.
        self.kept: list[Path] = []

    # -- deciding --------------------------------------------------------------------------
    def _differs(self, path: Path, distance: float, old_exists: bool, where: str = "",
                 rtol: float = numeric_diff.RTOL) -> bool:
        """Record the outcome for ``path``; whether it must be (re)written."""
        if distance <= rtol:
            self.kept.append(path)
            return False
        if not old_exists:
            why = "missing"
        elif math.isinf(distance):
            why = "differs in more than numbers"
        else:
            why = f"numbers differ by {distance:.1e} of their scale (tolerance {rtol:.0e})"
        self.differences.append(Difference(path, distance, why + where))
        return not self.check

    def _write_text(self, path: Path, text: str) -> Path:
        path.parent.mkdir(parents=True, exist_ok=True)
        safe_write.write_text(path, text, "path")
        self.written.append(path)
        return path

    # -- the kinds of output ---------------------------------------------------------------
    def text(self, name, text: str) -> Path:
        """A text output (Markdown, CSV).

        Parameters
        ----------
        name : str or pathlib.Path
            The file, relative to the output folder.
        text : str
            Its new content.

        Returns
        -------
        pathlib.Path
            The file.
        """
        path = self.outdir / name
        old = _read_text(path)
        distance = math.inf if old is None else numeric_diff.text_distance(old, text)
        if self._differs(path, distance, old is not None):
            self._write_text(path, text)
        return path

    def json(self, name, text: str) -> Path:
        """A JSON output, compared without its ``"made_by"`` record.

        Parameters
        ----------
        name : str or pathlib.Path
            The file, relative to the output folder.
        text : str
            Its new content, JSON.

        Returns
        -------
        pathlib.Path
            The file.
        """
        path = self.outdir / name
        old = _read_text(path)
        distance = math.inf
        if old is not None:
            try:
                before = json.dumps(_without_provenance(json.loads(old)), indent=1, sort_keys=True)
            except (ValueError, RecursionError):
                before = None
            if before is not None:
                after = json.dumps(_without_provenance(json.loads(text)), indent=1, sort_keys=True)
                distance = numeric_diff.text_distance(before, after)
        if self._differs(path, distance, old is not None):
            self._write_text(path, text)
        return path

    def plan(self, result, name) -> Path:
        """A plan file (:meth:`nonholo.io.result.PlanResult.to_json`), as :meth:`json`.

        Parameters
        ----------
        result : PlanResult
            The plan.
        name : str or pathlib.Path
            The file, relative to the output folder.

        Returns
        -------
        pathlib.Path
            The file.
        """
        return self.json(name, result.to_json())

    def _drawn(self, paths: list[Path], stem: str, words: list[str], numbers, make,
               rtol: float = numeric_diff.RTOL) -> list[Path]:
        record = self.outdir / DATA_DIR / f"{stem}.data"
        stored = _read_bytes(record)
        old = None
        if stored is not None:
            try:
                old = figure_data.from_bytes(stored)
            except ValueError:
                old = None
        present = all(p.is_file() for p in paths)
        if old is None or not present:
            distance = math.inf
        else:       # texts by their words and numbers (a rounded label), then the data
            distance = max(numeric_diff.text_distance("\n".join(old[0]), "\n".join(words)),
                           numeric_diff.array_distance(old[1], numbers))
        where = "" if old is None or distance <= rtol else _where(old, (words, numbers), rtol)
        if self._differs(paths[0], distance, present and old is not None, where, rtol):
            make()
            record.parent.mkdir(parents=True, exist_ok=True)
            safe_write.write_bytes(record, figure_data.to_bytes(words, numbers), "path")
            self.written.extend([*paths, record])
        return paths

    def figure(self, fig, stem: str, rtol: float = numeric_diff.RTOL) -> list[Path]:
        """A figure as ``<stem>.png`` and ``<stem>.pdf``, redrawn where its data moved.

        Parameters
        ----------
        fig : matplotlib.figure.Figure
            The figure.
        stem : str
            The files' name without suffix.
        rtol : float
            The tolerance of its data, for a figure of numbers known only to a coarser one
            (the default: :data:`nonholo.io.numeric_diff.RTOL`).

        Returns
        -------
        list of pathlib.Path
            The PNG's and the PDF's paths.
        """
        words, numbers = figure_data.figure_data(fig)
        paths = [self.outdir / f"{stem}.png", self.outdir / f"{stem}.pdf"]
        return self._drawn(paths, stem, words, numbers,
                           lambda: style.save_figure(fig, stem, self.outdir, dpi=self.dpi), rtol)

    def drawing(self, name, make, words: list[str], numbers) -> Path:
        """A file drawn by ``make(path)`` from ``numbers``, remade where they moved.

        Parameters
        ----------
        name : str or pathlib.Path
            The file, relative to the output folder.
        make : callable
            Writes the file at the path it is given.
        words : list of str
            What it shows, in words (a change remakes it).
        numbers : array_like
            The numbers it is drawn from.

        Returns
        -------
        pathlib.Path
            The file.
        """
        path = self.outdir / name
        self._drawn([path], Path(name).name, list(words), np.ravel(np.asarray(numbers, dtype=float)),
                    lambda: make(path))
        return path
