"""The global route: a goal the local planner cannot reach, reached hop by hop along a path
of orientations through the start's component.

:func:`steer` takes the path of :func:`nonholo.roadmap.orientation_path` (hops of at most
:data:`nonholo.roadmap.MAX_HOP` rad, clear of ``Δ = 0``) and plans each hop with the
local planner (``local(R_start, R_goal, T)``: :func:`nonholo.plan` with the run's
strategy and options, route ``"local"``), from where the previous hop's certified replay
ended, so that no hop's error carries into the next. A hop that fails is split at its
geodesic midpoint (down to :data:`MIN_HOP` rad, at most :data:`MAX_PIECES` pieces in
all). The hops' physical controls are stitched into one control on ``[0, T]``, an equal
time share each (:class:`~nonholo.stitched.Stitched`); the stitched control is then
certified as a whole (:func:`nonholo.certify.measure`). Where that replay misses the goal
by more than ``tol`` allows, the last hop is planned again from where the stitched replay
enters it.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .. import certify, roadmap, so3
from ..certify import Certificate
from ..mechanism import Mechanism
from ..stitched import Stitched

#: The shortest hop a failed hop is split into (rad).
MIN_HOP = 0.02
#: Pieces of a stitched control at most.
MAX_PIECES = 64
#: A hop planned with a larger sensitivity is split instead: the stitched motion's
#: sensitivity grows like the product of its hops'.
MAX_HOP_SENSITIVITY = 10.0
#: Re-plans of the last hop from the stitched replay at most.
MAX_REPAIRS = 2


@dataclass
class Steered:
    """What :func:`steer` made of a route: the stitched control (``None`` if a hop failed),
    its certificate, the hops' results and why it failed."""

    controls: Stitched | None
    certificate: Certificate | None
    hops: list = field(default_factory=list)
    reason: str = ""
    path: np.ndarray | None = None


def _stitch(T: float, hops: list, R0) -> Stitched:
    return Stitched(T, [h.parametrisation for h in hops], [R0] + [h.Rd for h in hops])


def steer(mechanism: Mechanism, R0, Rd, T: float, local: Callable, *, tol: float, delta_min: float,
          sign: float) -> Steered:
    """The route ``R0 → Rd`` steered hop by hop (see the module)."""
    path = roadmap.orientation_path(mechanism, R0, Rd, delta_min=delta_min)
    if path is None:
        return Steered(None, None, reason="no path of orientations clear of Δ = 0 joins the start and "
                                          "the goal on the roadmap")
    T_hop = T / (len(path) - 1)
    targets = list(path[1:])
    hops = []
    R = np.asarray(R0, dtype=float)
    while targets:
        if len(hops) + len(targets) > MAX_PIECES:
            return Steered(None, None, hops, f"the route needs more than {MAX_PIECES} hops", path)
        res = local(R, targets[0], T_hop)
        if res.success and res.sensitivity <= MAX_HOP_SENSITIVITY:
            hops.append(res)
            R = res.R_T
            targets.pop(0)
            continue
        length = so3.distance(R, targets[0])
        if length / 2 < MIN_HOP:
            why = res.reason if not res.success else f"sensitivity {res.sensitivity:.3g}"
            return Steered(None, None, hops, f"hop {len(hops) + 1} ({length:.3g} rad) failed: {why}", path)
        targets.insert(0, roadmap.geodesic(R, targets[0], [0.5])[0])
    cert = None
    for repair in range(MAX_REPAIRS + 1):
        stitched = _stitch(T, hops, R0)
        k = len(hops)
        M = k * max(h.replay_steps for h in hops)
        cert = certify.measure(R0, Rd, T, mechanism, stitched, M, tol, delta_min, sign)
        if cert.passed or not cert.correctable or repair == MAX_REPAIRS:
            break
        # the last hop again, from where the stitched replay enters it
        entry = cert.R[(k - 1) * (cert.replay_steps // k)]
        res = local(entry, Rd, hops[-1].T)
        if not res.success:
            break
        hops[-1] = res
    if not cert.passed:
        return Steered(None, cert, hops, f"the stitched control is not certified: {cert.reason}", path)
    return Steered(stitched, cert, hops, "", path)
