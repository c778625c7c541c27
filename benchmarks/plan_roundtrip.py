"""Every plan saves and loads: leg-speed plans of random platform pairs, saved by
:meth:`~nonholo.io.result.PlanResult.save` and read back by
:meth:`~nonholo.io.result.PlanResult.load`.

Pairs: :func:`benchmarks.goalset.uniform_pairs` of ``platform`` (Haar-uniform, one component),
each planned twice with a ``LegSpeed`` (default 0.5): in the given ``T = 1`` and in the least
time (``T=None``) — successes (local and global routes, re-timed or not) and failures (too
slow for ``T``, not converged) alike. A plan passes when ``save`` writes it, ``load`` reads
it back and the loaded plan equals the saved one field by field. Run as::

    python -m benchmarks.plan_roundtrip --pairs 40 [--seed 7] [--leg-speed 0.5] [--out results.json]

Prints one line per plan and a summary; exit status 1 if any plan failed to round-trip.
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

from nonholo.io.result import PlanResult
from nonholo.constraints import LegSpeed
from nonholo.planning.api import plan

from . import goalset


def round_trip(res: PlanResult, path: Path) -> str | None:
    """``None`` if ``res`` saves to ``path`` and loads back equal, else what went wrong."""
    try:
        res.save(path)
    except ValueError as exc:
        return f"save refused: {exc}"
    try:
        back = PlanResult.load(path)
    except ValueError as exc:
        return f"load refused: {exc}"
    return None if back == res else "loaded plan differs from the saved one"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--pairs", type=int, default=40)
    p.add_argument("--seed", type=int, default=goalset.SEED)
    p.add_argument("--leg-speed", type=float, default=0.5)
    p.add_argument("--out", default=None, help="write one record per plan as JSON here")
    args = p.parse_args(argv)
    pairs = goalset.uniform_pairs("platform", args.pairs, seed=args.seed)
    records = []
    with tempfile.TemporaryDirectory() as tmp:
        for i, pair in enumerate(pairs):
            for T in (1.0, None):
                t0 = time.perf_counter()
                res = plan(pair["R0"], pair["Rd"], T=T, constraints=[LegSpeed(args.leg_speed)])
                problem = round_trip(res, Path(tmp) / f"plan{i}_{T}.json")
                rec = {"pair": pair["id"], "T": T, "success": bool(res.success), "route": res.route,
                       "kind": res.parametrisation.kind, "round_trip": problem is None,
                       "problem": problem, "seconds": time.perf_counter() - t0}
                records.append(rec)
                print(f"{pair['id']} T={T}: {'success' if res.success else 'FAILED '} {res.route:6s} "
                      f"{rec['kind']:9s} {'ok' if problem is None else problem}", flush=True)
    bad = [r for r in records if not r["round_trip"]]
    succ = sum(r["success"] for r in records)
    glob = sum(r["route"] == "global" for r in records)
    print(f"{len(records)} plans ({succ} successes, {len(records) - succ} failures, {glob} global routes): "
          f"{len(records) - len(bad)} saved and reloaded equal, {len(bad)} did not")
    if args.out:
        Path(args.out).write_text(json.dumps(records, indent=1) + "\n")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
