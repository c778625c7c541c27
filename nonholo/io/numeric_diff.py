"""How far apart two outputs are, number by number: texts (JSON, CSV, Markdown) and arrays.

Two outputs *agree* when everything but their numbers is the same and every pair of
numbers ``a``, ``b`` is within :data:`RTOL` of their magnitude, or of 1 where they are
smaller::

    |a - b| <= RTOL * max(1, |a|, |b|)

so that a quantity at rounding level (a terminal error of 2e-11 rad, a slip of 1e-17) is
noise on every scale, and a change of a digit in a rounded label (``1.8e-11`` against
``1.9e-11``) is one only where it matters. :func:`distance` gives the largest such
difference in units of that scale (0 when both are equal; ``inf`` where the texts differ in
anything but numbers), so ``distance(a, b) <= RTOL`` is the test.

A number in a text is what :data:`NUMBER` matches: an optional sign, digits with an
optional fraction, an optional exponent; ``example1_parametric`` holds the number 1.
"""
from __future__ import annotations

import math
import re

import numpy as np

__all__ = ["RTOL", "NUMBER", "distance", "text_distance", "array_distance", "agree"]

#: The relative tolerance of two numbers (see the module).
RTOL = 1e-9
#: A number in a text.
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _split(text: str) -> tuple[list[str], list[float]]:
    """The text around the numbers, and the numbers."""
    words, numbers, at = [], [], 0
    for m in NUMBER.finditer(text):
        words.append(text[at:m.start()])
        numbers.append(float(m.group()))
        at = m.end()
    words.append(text[at:])
    return words, numbers


def text_distance(a: str, b: str) -> float:
    """The largest difference of two texts' numbers, in units of their scale (see the module).

    Parameters
    ----------
    a, b : str
        The texts.

    Returns
    -------
    float
        0 for equal texts, ``inf`` where they differ in anything but numbers.
    """
    if a == b:
        return 0.0
    words_a, numbers_a = _split(a)
    words_b, numbers_b = _split(b)
    if words_a != words_b:
        return math.inf
    return array_distance(np.array(numbers_a), np.array(numbers_b))


def array_distance(a, b) -> float:
    """The largest difference of two arrays, element by element, in units of their scale.

    Parameters
    ----------
    a, b : array_like
        Arrays of numbers.

    Returns
    -------
    float
        ``inf`` for arrays of different shapes, or where one is NaN or infinite and the
        other not the same.
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape:
        return math.inf
    if a.size == 0:
        return 0.0
    same = (a == b) | (np.isnan(a) & np.isnan(b))
    if same.all():
        return 0.0
    a, b = a[~same], b[~same]
    if not (np.isfinite(a).all() and np.isfinite(b).all()):
        return math.inf
    scale = np.maximum(1.0, np.maximum(np.abs(a), np.abs(b)))
    return float(np.max(np.abs(a - b) / scale))


def distance(a, b) -> float:
    """:func:`text_distance` of two texts, :func:`array_distance` of anything else.

    Parameters
    ----------
    a, b : str or array_like
        Two texts or two arrays.

    Returns
    -------
    float
        The largest difference in units of the scale.
    """
    if isinstance(a, str) and isinstance(b, str):
        return text_distance(a, b)
    return array_distance(a, b)


def agree(a, b) -> bool:
    """Whether two texts or arrays agree within :data:`RTOL` (see the module).

    Parameters
    ----------
    a, b : str or array_like
        Two texts or two arrays.

    Returns
    -------
    bool
        ``distance(a, b) <= RTOL``.
    """
    return distance(a, b) <= RTOL
