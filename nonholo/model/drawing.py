"""How a mechanism is drawn: planar bodies and wheels placed by expressions in its
coordinates (a catalog vehicle's, or a mechanism file's ``[drawing]``)."""
from __future__ import annotations


def catalog_drawing(name: str):
    """The drawing of the catalog's mechanism ``name``; ``None`` for one without.

    Parameters
    ----------
    name : str
        A catalog name.

    Returns
    -------
    Drawing or None
        Its drawing.
    """
    return None
