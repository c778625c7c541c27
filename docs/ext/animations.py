"""The gallery's animations: one GIF per catalog mechanism in ``docs/gallery/animations/``,
shown by ``docs/gallery/animations.md``.

Each mechanism's classic problem is planned with the defaults and animated by
:func:`nonholo.viz.animate` with few frames at a low resolution, so that every GIF stays
small (a few hundred KB at most). Run from the repository's root::

    python docs/ext/animations.py            # every mechanism
    python docs/ext/animations.py car        # some

and commit the GIFs it writes (the documentation build only shows them).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "gallery" / "animations"
#: frames and frames per second of every GIF, and their resolution (by mechanism; ``None``:
#: the others'), for GIFs of at most about 400 KB
FRAMES, FPS = 36, 12
DPI = {None: 60, "rolling_ball": 54}


def problems() -> dict:
    """Each catalog mechanism's problem: ``{name: (start, goal, plan's keywords)}``.

    Returns
    -------
    dict
        The problems by mechanism name.
    """
    from nonholo import Settings
    from nonholo.paper import examples
    from nonholo.spaces import so3

    example = examples.get(1)
    R_ball = so3.from_rpy(0.4, -0.3, 0.2)
    return {
        "platform": (example.R_start, example.R_goal, {}),
        "platform_raised": (np.eye(3), so3.from_rpy(0.5, 0.3, -0.3), {}),
        "attitude": (so3.from_rpy(0.1, 0.2, 0.3), so3.from_rpy(0.8, -0.4, 0.5), {}),
        "rolling_ball": ((R_ball, (0.0, 0.0)), (so3.exp(np.array([np.pi / 2, 0.0, 0.0])) @ R_ball, (0.0, 0.0)),
                         {"strategy": "paper", "settings": Settings(harmonics=4)}),
        "car": ((0.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0), {}),
        "brockett": ((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), {}),
        "unicycle": ((0.0, 0.0, 0.0), (0.0, 1.0, 0.0), {}),
    }


def main(argv: list[str] | None = None) -> int:
    """Plan and animate the named mechanisms (default: all).

    Parameters
    ----------
    argv : list of str, optional
        Mechanism names.

    Returns
    -------
    int
        The exit status.
    """
    sys.path.insert(0, str(ROOT))
    import nonholo
    from nonholo import viz

    every = problems()
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("names", nargs="*", metavar="NAME", help=f"mechanisms (default: all: {', '.join(every)})")
    names = parser.parse_args(argv).names or list(every)
    unknown = [n for n in names if n not in every]
    if unknown:
        parser.error(f"unknown mechanism {unknown[0]!r}; known: {', '.join(every)}")
    OUT.mkdir(parents=True, exist_ok=True)
    for name in names:
        start, goal, options = every[name]
        t0 = time.perf_counter()
        result = nonholo.plan(start, goal, mechanism=name, **options)
        if not result.success:
            print(f"{name}: not planned ({result.reason})", file=sys.stderr)
            return 1
        path = viz.animate(result, OUT / f"{name}.gif", frames=FRAMES, fps=FPS, dpi=DPI.get(name, DPI[None]))
        print(f"wrote {path.relative_to(ROOT)} ({path.stat().st_size / 1024:.0f} KB, "
              f"{time.perf_counter() - t0:.1f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
