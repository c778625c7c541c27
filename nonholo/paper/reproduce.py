"""The main job: check the generated code, audit the appendix, solve the examples, draw.

``nonholo reproduce`` (see :func:`run`) writes into ``paper_figures/``:

- the figures of the mechanism, its singular set and of every example (PNG and PDF);
- an animation of the platform through Example 3 (GIF);
- ``global_route``: a far goal (:data:`FAR_GOAL`) that the local planner misses, reached
  by the global route (figure, and ``plans/far_goal.json``);
- ``leg_limits``: a goal (:data:`LIMITS_GOAL`) planned without and with the legs' stroke
  limits :data:`LEG_LENGTH` (figure; ``plans/leg_limits.json`` and ``plans/leg_limits.csv``,
  the motion for an actuator controller);
- ``motion_quality``: the same goal's default plan, its least-energy plan
  (``objective="energy"``) and the plan re-timed in the least time under the legs' speed
  bound :data:`LEG_SPEED` (figure; ``plans/least_time.json`` and ``plans/least_time.csv``);
- ``least_time_vehicle``: the unicycle's obstacle-free park :data:`VEHICLE_PARK` in the least
  time under :data:`VEHICLE_BOUNDS` (``objective="time"``) against the plan as found re-timed
  along its path (figure);
- ``physics_example3``, ``physics_rolling_ball``, ``physics_car``: Example 3, the ball's
  reorientation in place and the car's parking played on their mechanisms' MuJoCo models
  with three touch-ups (:func:`nonholo.physics.execution.execute`; figures of
  :func:`nonholo.viz.execution_figures.execution_figure`), when MuJoCo is installed (the
  ``physics`` extra; without it a note says they were skipped);
- ``plans/example<k>_<method>.json``: every planned result (reload with
  :meth:`nonholo.io.result.PlanResult.load`);
- ``summary.json``: ``{"made_by": ..., "examples": [...]}``, one object per (example,
  method) with ``example``, ``method``, ``strategy``, ``success``, ``iterations``,
  ``terminal_error`` (after independent re-simulation with DOP853), ``planner_error``
  (the planner's own ``|l_T|``), ``min_delta``, ``reason``; and ``summary.md``, the same
  as a table;
- ``figure_data/<stem>.data``: the data each figure and the animation were drawn from
  (:mod:`nonholo.paper.outputs`).

An output is rewritten only where its content differs beyond the tolerances of
:mod:`nonholo.paper.outputs` from the file already there (numbers within 1e-9 of their
magnitude, or of 1 where smaller; figures redrawn only when the data they plot moved), so
a run on another CPU leaves a fresh clone as it was. ``summary.json`` and every plan file
record what made them (``"made_by"``: :mod:`nonholo.io.provenance`). No file records when
or how fast it was made — PDFs carry no creation date (:func:`nonholo.viz.style.save_figure`),
plan files no wall time (``seconds`` is ``null``): two runs on one machine write the same
bytes. The times go to the terminal: one line per plan on stderr and the summary table
with a time column on stdout. ``check=True`` (``nonholo reproduce --check``) writes
nothing and lists each output that differs, and by how much.

The run fails (exit status 1) when the generated code is stale or Example 1 or 2 fails, or,
with ``check``, when an output differs beyond the tolerances.
"""
from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..certify.resimulate import resimulate, terminal_error
from ..io import csv_export, provenance
from ..model import catalog
from ..planning.api import STRATEGIES, plan
from ..model.bounds import InputBounds
from ..planning.constraint_objects import LegStroke
from ..planning.settings import Settings
from ..planning.retime import retime
from ..spaces import so3
from .. import viz
from ..viz import state_figures
from . import examples as _examples
from .outputs import Outputs

DEFAULT_OUTDIR = Path("paper_figures")
#: Re-simulated terminal error required of Examples 1 and 2 (rad).
RESIM_TOL = 1e-8
#: A far goal (RPY of start and goal, rad; 2.76 rad apart) that the local planner misses
#: and the global route reaches: the first pair of the 1.8–π band of
#: ``benchmarks.goalset.band_pairs("platform", 500)``, rounded.
FAR_GOAL = ((-1.918, 0.336, -2.521), (1.433, -0.813, 1.324))
#: A goal (RPY angles of start and goal) whose plan without limits takes leg 1 below 1.2,
#: planned again with :data:`LEG_LENGTH` (figure ``leg_limits``, ``plans/leg_limits.json``
#: and ``.csv``).
LIMITS_GOAL = ((0.5, 1.2, -0.5), (-0.4527, 1.4094, -1.3638))
#: the legs' stroke of the limits example (:data:`LIMITS_GOAL`)
LEG_LENGTH = (1.2, 2.0)
#: The legs' speed bound the same goal's default plan is re-timed under (figure
#: ``motion_quality``, ``plans/least_time.json`` and ``.csv``), in radius per second (the
#: length unit of the geometry, :mod:`nonholo.model.names`).
LEG_SPEED = 0.5
#: The least-time vehicle: Dynobench's obstacle-free unicycle park (start, goal).
VEHICLE_PARK = ((0.7, 0.8, 0.0), (1.9, 0.3, 0.0))
#: The bounds ``(low, high)`` of the unicycle's inputs ``v``, ``ω`` in :data:`VEHICLE_PARK`.
VEHICLE_BOUNDS = ((-0.5, -0.5), (0.5, 0.5))


def strongest_strategy() -> str:
    """The strongest strategy there is.

    Returns
    -------
    str
        ``"robust"`` when the project has it, else ``"paper"``.
    """
    return "robust" if "robust" in STRATEGIES else "paper"


@dataclass
class Solved:
    """One example planned with one method, and the plan re-simulated independently.

    Parameters
    ----------
    example : Example
        The example (:class:`nonholo.paper.examples.Example`).
    result : PlanResult
        Its plan.
    resim_error : float or None
        The terminal error of the plan re-simulated by DOP853 (``None``: no samples).
    """

    example: _examples.Example
    result: object  # PlanResult
    resim_error: float | None

    @property
    def ok(self) -> bool:
        """Whether the plan succeeded and its re-simulation ends within :data:`RESIM_TOL`."""
        return bool(self.result.success and self.resim_error is not None
                    and self.resim_error <= RESIM_TOL)

    def summary(self) -> dict:
        """The row of ``summary.json`` (see the module).

        Returns
        -------
        dict
            ``example``, ``method``, ``strategy``, ``success``, ``iterations``,
            ``terminal_error``, ``planner_error``, ``min_delta``, ``reason``.
        """
        r = self.result
        return {"example": self.example.number, "method": r.method, "strategy": r.strategy,
                "success": self.ok, "iterations": r.iterations,
                "terminal_error": self.resim_error, "planner_error": r.terminal_error,
                "min_delta": r.min_delta, "reason": r.reason}


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def keep(result, name, outputs: Outputs) -> Path:
    """Save a plan without its wall time (see the module), where it differs.

    Parameters
    ----------
    result : PlanResult
        The plan.
    name : str or pathlib.Path
        The plan file, relative to the output folder.
    outputs : Outputs
        The output folder's writer.

    Returns
    -------
    pathlib.Path
        The plan file.
    """
    return outputs.plan(replace(result, seconds=None), name)


def solve(example: _examples.Example, method: str, strategy: str) -> Solved:
    """Plan one example with one method and re-simulate the plan independently.

    Parameters
    ----------
    example : Example
        The example.
    method : str
        ``"parametric"`` or ``"nonparametric"``.
    strategy : str
        The strategy.

    Returns
    -------
    Solved
        The plan and its re-simulated error.
    """
    result = plan(example.R_start, example.R_goal, T=example.T, strategy=strategy, objective=None,
                  settings=Settings(method=method, harmonics=example.harmonics))
    resim = None
    if len(result.R):
        R_T = resimulate(example.R_start, result.controls, example.T,
                         mechanism=result.mechanism, breakpoints=result.breakpoints)
        resim = terminal_error(R_T, example.R_goal)
    return Solved(example, result, resim)


def solve_all(progress=_log) -> list[Solved]:
    """Every example with each of its methods (Example 3: the strongest strategy).

    Parameters
    ----------
    progress : callable, optional
        Called with a line of progress (default: printed on stderr).

    Returns
    -------
    list of Solved
        The plans, in the examples' order.
    """
    jobs = [(ex, m, "paper" if ex.must_succeed else strongest_strategy())
            for ex in _examples.examples() for m in ex.methods]
    solved = []
    for k, (ex, method, strategy) in enumerate(jobs, 1):
        progress(f"[{k}/{len(jobs)}] {ex.title}: {method}, strategy {strategy} ...")
        s = solve(ex, method, strategy)
        r = s.result
        err = "n/a" if s.resim_error is None else f"{s.resim_error:.2e}"
        md = "n/a" if r.min_delta is None else f"{r.min_delta:.3f}"
        progress(f"      {'ok' if s.ok else 'FAILED'}: {r.iterations} iterations, "
                 f"re-simulated |l_T| = {err}, min |Δ| = {md}, {r.seconds:.3f} s"
                 + ("" if s.ok else f" ({r.reason})"))
        solved.append(s)
    return solved


#: Options of the plan of each card of a mechanism beyond SO(3): the ball's default plan rolls 12 radii out and back;
#: the paper's strategy with four harmonics finds one within 2 radii (a fraction of the
#: default's energy ∫|v|² dt), the motion one wants to see.
STATE_OPTIONS = {"rolling_ball": {"strategy": "paper", "settings": Settings(harmonics=4)}, "car": {}}
#: The classic problems of the mechanisms beyond SO(3) (start, goal): the ball turned by
#: π/2 about a horizontal axis in place, the car parked one wheelbase sideways.
STATE_PROBLEMS = {
    "rolling_ball": ((so3.from_rpy(0.4, -0.3, 0.2), (0.0, 0.0)),
                     (so3.exp(np.array([np.pi / 2, 0.0, 0.0])) @ so3.from_rpy(0.4, -0.3, 0.2), (0.0, 0.0))),
    "car": ((0.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0)),
}
#: How the plan of each of :data:`STATE_PROBLEMS` is drawn.
STATE_FIGURES = {"rolling_ball": state_figures.ball_figure, "car": state_figures.car_figure}
#: The planned motion (start, goal) of the card of a mechanism without a problem or a geometry
#: of its own, by its state space.
CARD_PROBLEMS = {"SO(3)": (so3.from_rpy(0.1, 0.2, 0.3), so3.from_rpy(0.8, -0.4, 0.5))}


def mechanism_cards():
    """``(figure, stem)`` of every mechanism: the platforms at a regular pose with their
    singular sets, the others with a planned motion (:data:`CARD_PROBLEMS` on SO(3): RPY(0.1, 0.2,
    0.3) → RPY(0.8, -0.4, 0.5)); of those beyond SO(3), the ones with a drawing
    (:data:`STATE_PROBLEMS`).

    Yields
    ------
    figure : matplotlib.figure.Figure
        The mechanism's card.
    stem : str
        Its file's stem, ``mechanism_<name>``.
    """
    for name in catalog.names():
        mech = catalog.get(name)
        if name in STATE_PROBLEMS:
            start, goal = STATE_PROBLEMS[name]
            draw = STATE_FIGURES[name]
            yield draw(plan(start, goal, mechanism=name, **STATE_OPTIONS[name])), f"mechanism_{name}"
        elif mech.geometry is not None:
            R = np.eye(3) if abs(mech.singular.value(np.eye(3))) > 0.1 else _examples.get(1).R_start
            psi = float(so3.as_rpy(R)[2])
            yield viz.mechanism_card_figure(name, R=R, psi_slice=psi), f"mechanism_{name}"
        elif mech.space.name in CARD_PROBLEMS:
            result = plan(*CARD_PROBLEMS[mech.space.name], mechanism=name)
            yield viz.mechanism_card_figure(name, result=result), f"mechanism_{name}"


def plan_limits_goal():
    """:data:`LIMITS_GOAL` planned with the defaults, without and with ``leg_length=LEG_LENGTH``.

    Returns
    -------
    free : PlanResult
        The plan without limits.
    limited : PlanResult
        The plan within :data:`LEG_LENGTH`.
    """
    R0, Rd = (so3.from_rpy(*a) for a in LIMITS_GOAL)
    return plan(R0, Rd), plan(R0, Rd, constraints=[LegStroke(*LEG_LENGTH)])


def plan_quality(free):
    """:data:`LIMITS_GOAL` of least energy, and its default plan re-timed in the least time.

    Parameters
    ----------
    free : PlanResult
        :data:`LIMITS_GOAL`'s default plan.

    Returns
    -------
    cheap : PlanResult
        The goal planned with ``objective="energy"``.
    fast : PlanResult
        ``free`` re-timed in the least time under :data:`LEG_SPEED`.
    """
    R0, Rd = (so3.from_rpy(*a) for a in LIMITS_GOAL)
    return plan(R0, Rd, objective="energy"), retime(free, LEG_SPEED)


def plan_vehicle_least_time():
    """:data:`VEHICLE_PARK` in the least time under :data:`VEHICLE_BOUNDS` (``objective="time"``),
    and the plan as found re-timed along its path (``T=None``).

    Returns
    -------
    fastest : PlanResult
        The path of least time.
    along : PlanResult
        The plan as found, re-timed.
    bounds : InputBounds
        The bounds.
    """
    bounds = InputBounds(*VEHICLE_BOUNDS)
    start, goal = VEHICLE_PARK
    return (plan(start, goal, mechanism="unicycle", objective="time", constraints=[bounds]),
            plan(start, goal, mechanism="unicycle", T=None, constraints=[bounds]), bounds)


def plan_far_goal():
    """:data:`FAR_GOAL` planned by :func:`nonholo.plan` with its defaults.

    Returns
    -------
    PlanResult
        The plan.
    """
    return plan(so3.from_rpy(*FAR_GOAL[0]), so3.from_rpy(*FAR_GOAL[1]))


def write_figures(solved: list[Solved], outputs: Outputs, progress=_log) -> None:
    """Write all figures of the mechanism, the singular set and the examples, where they differ.

    Also the plans of the far goal, the stroke-limits goal and the least-time plan (see
    the module).

    Parameters
    ----------
    solved : list of Solved
        The examples' plans.
    outputs : Outputs
        The output folder's writer (:mod:`nonholo.paper.outputs`).
    progress : callable, optional
        Called with a line of progress (default: printed on stderr).
    """
    def save(fig, stem):
        before = len(outputs.written)
        outputs.figure(fig, stem)
        progress(f"      {'wrote' if len(outputs.written) > before else 'kept'} {stem}.png/.pdf")

    exs = _examples.examples()
    for fig, stem in mechanism_cards():
        save(fig, stem)
    ex1 = _examples.get(1)  # its start and goal lie in the slice ψ = -0.5 drawn on the right
    marks = {"Example 1 start": (*ex1.rpy_start[:2], "o"),
             "Example 1 goal": (*ex1.rpy_goal[:2], "X")}
    save(viz.singular_set_figure(psi_slice=ex1.rpy_start[2], marks=marks), "singular_set")
    save(viz.singular_slices_figure(), "singular_set_slices")
    save(viz.normal_form_figure(), "normal_form")
    for ex in exs:
        save(viz.mechanism_figure(ex.R_start, ex.R_goal, title=f"{ex.title}: start and goal"),
             f"example{ex.number}_mechanism")
        results = [s.result for s in solved if s.example.number == ex.number and len(s.result.R)]
        if not results:
            continue
        stem = f"example{ex.number}"
        save(viz.example_overview_figure(results, title=f"{ex.title} ({ex.description})"),
             f"{stem}_overview")
        save(viz.convergence_figure(results), f"{stem}_convergence")
        save(viz.controls_figure(results), f"{stem}_controls")
        save(viz.rpy_figure(results), f"{stem}_rpy")
        save(viz.leg_lengths_figure(results), f"{stem}_leg_lengths")
        save(viz.delta_figure(results), f"{stem}_delta")
    far = plan_far_goal()
    if far.route == "global":
        save(viz.global_route_figure(far), "global_route")
    else:
        progress(f"      note: the far goal took the {far.route} route ({far.reason[:120]}); no global_route figure")
    keep(far, "plans/far_goal.json", outputs)
    free, limited = plan_limits_goal()
    if free.success and limited.success:
        save(viz.leg_limits_figure(free, limited), "leg_limits")
        keep(limited, "plans/leg_limits.json", outputs)
        outputs.text("plans/leg_limits.csv", csv_export.csv_text(limited, 100))
        progress("      plans/leg_limits.json and plans/leg_limits.csv")
    else:
        progress(f"      note: the stroke-limits goal was not solved ({limited.reason[:120]}); no leg_limits figure")
    if free.success:
        cheap, fast = plan_quality(free)
        save(viz.motion_quality_figure(free, cheap, fast), "motion_quality")
        keep(fast, "plans/least_time.json", outputs)
        outputs.text("plans/least_time.csv", csv_export.csv_text(fast, 100))
        progress("      plans/least_time.json and plans/least_time.csv")
    fastest, along, bounds = plan_vehicle_least_time()
    if fastest.success and along.success:
        save(viz.least_time_figure(fastest, along, bounds), "least_time_vehicle")
    else:
        progress(f"      note: the unicycle's park was not solved ({fastest.reason[:120]}); no least_time_vehicle figure")
    ex3 = [s for s in solved if s.example.number == 3 and len(s.result.R)]
    if ex3:
        motion = ex3[0].result
        outputs.drawing("example3_animation.gif", lambda path: viz.animate_platform(motion, path),
                        ["animate_platform", motion.mechanism, motion.method],
                        np.concatenate([motion.t, np.ravel(motion.R)]))
        progress("      example3_animation.gif")
    physics_figures(ex3[0].result if ex3 else None, outputs, progress)


#: Touch-ups of the executions :func:`physics_figures` draws.
PHYSICS_TOUCH_UPS = 3
#: The tolerance of the physics figures' data (:meth:`Outputs.figure`). A touch-up is
#: planned from the state measured on the model, which the plan played before it moved by
#: rounding; the new plan converges to the plan's ``tol`` (1e-10) from there, and its
#: controls are determined only to that times their sensitivity (up to about 1e3): another
#: CPU's touch-ups move by up to about 1e-7 (4.8e-8 measured between the native and numba
#: kernels), so the figures drawn from them are compared to 1e-6.
TOUCH_UP_RTOL = 1e-6


def physics_figures(example3, outputs: Outputs, progress=_log) -> None:
    """Example 3, the ball's reorientation and the car's parking played on physics models.

    Parameters
    ----------
    example3 : PlanResult or None
        Example 3's plan (``None``: not drawn).
    outputs : Outputs
        The output folder's writer (none written without MuJoCo).
    progress : callable, optional
        Called with a line of progress.
    """
    try:
        import mujoco  # noqa: F401  (the physics extra)
    except ImportError:
        progress("      note: MuJoCo is not installed (python -m pip install -e '.[physics]'): "
                 "no physics figures")
        return
    from ..physics import execute

    runs = [("physics_example3", "Example 3 on the platform's physics model", example3)]
    for name in ("rolling_ball", "car"):
        start, goal = STATE_PROBLEMS[name]
        runs.append((f"physics_{name}", None, plan(start, goal, mechanism=name, **STATE_OPTIONS[name])))
    for stem, title, result in runs:
        if result is None or not result.success:
            progress(f"      note: no plan to play for {stem}")
            continue
        record = execute(result, touch_ups=PHYSICS_TOUCH_UPS)
        errors = ", ".join(" / ".join(f"{v:.1e}" for v in s["error"].values()) for s in record.stages
                           if s.get("outcome", "played") == "played")
        ended = record.stages[-1]
        why = "" if ended.get("outcome", "played") == "played" else f"; then not played: {ended['outcome']}"
        progress(f"      played {stem[8:]}: error after each stage played {errors}{why}")
        before = len(outputs.written)
        outputs.figure(viz.execution_figure(record, title=title), stem, rtol=TOUCH_UP_RTOL)
        progress(f"      {'wrote' if len(outputs.written) > before else 'kept'} {stem}.png/.pdf")


def summary_table(rows: list[dict], seconds: list[float] | None = None) -> str:
    """Markdown table of the summary rows.

    Parameters
    ----------
    rows : list of dict
        The rows (:meth:`Solved.summary`).
    seconds : list of float, optional
        Each row's wall time: a time column too (for the terminal, not for a file).

    Returns
    -------
    str
        The table.
    """
    timed = seconds is not None
    head = ("| example | method | strategy | success | iterations | re-simulated ‖l_T‖ [rad] "
            "| min \\|Δ\\| |" + (" time [s] |" if timed else "")
            + "\n|---|---|---|---|---|---|---|" + ("---|" if timed else ""))
    lines = [head]
    for k, r in enumerate(rows):
        err = "–" if r["terminal_error"] is None else f"{r['terminal_error']:.1e}"
        md = "–" if r["min_delta"] is None else f"{r['min_delta']:.3f}"
        lines.append(f"| {r['example']} | {r['method']} | {r['strategy']} | "
                     f"{'yes' if r['success'] else 'no'} | {r['iterations']} | {err} | {md} |"
                     + (f" {seconds[k]:.3f} |" if timed else ""))
    return "\n".join(lines)


def run(outdir: Path = DEFAULT_OUTDIR, audit: bool = True, draw: bool = True, check: bool = False) -> int:
    """The whole job (see the module).

    Parameters
    ----------
    outdir : pathlib.Path, default DEFAULT_OUTDIR
        The output folder.
    audit : bool, default True
        Whether to audit the appendix against the derivation.
    draw : bool, default True
        Whether to draw the figures.
    check : bool, default False
        Write nothing; list the outputs that differ from the files there, and by how much.

    Returns
    -------
    int
        The exit status: 1 when the generated code is stale or Example 1 or 2 fails, or with
        ``check`` when an output differs beyond the tolerances; else 0.
    """
    from derivations import audit as _audit
    from derivations import codegen

    from ..integrate import compiled
    from . import appendix_audit

    t0 = time.perf_counter()
    outdir = Path(outdir)
    if not check:
        outdir.mkdir(parents=True, exist_ok=True)
    outputs = Outputs(outdir, check=check)
    _log("checking that the generated modules match a fresh derivation ...")
    stale = codegen.check(files=compiled.generated_files())
    if stale:
        for path, _ in stale:
            _log(f"stale generated module: {path} (run `nonholo derive`)")
        return 1
    if audit:
        _log("auditing the appendix against the derivation ...")
        print(_audit.format_table(appendix_audit.run()), flush=True)
    _log("solving the examples ...")
    solved = solve_all()
    for s in solved:
        keep(s.result, f"plans/example{s.example.number}_{s.result.method}.json", outputs)
    rows = [s.summary() for s in solved]
    outputs.json("summary.json", json.dumps({"made_by": provenance.made_by(), "examples": rows},
                                            indent=2) + "\n")
    outputs.text("summary.md", summary_table(rows) + "\n")
    print(summary_table(rows, [s.result.seconds for s in solved]), flush=True)
    if draw:
        _log("drawing the figures ...")
        write_figures(solved, outputs)
    failed = [s for s in solved if s.example.must_succeed and not s.ok]
    for s in solved:
        if not s.example.must_succeed and not s.ok:
            _log(f"note: {s.example.title} not solved by strategy {s.result.strategy!r}: "
                 f"{s.result.reason}")
    _log(f"done in {time.perf_counter() - t0:.1f} s; {len(outputs.written)} files written, "
         f"{len(outputs.kept)} kept as they were (their content agrees); outputs in {outdir}/")
    for d in outputs.differences:
        if check:
            print(f"differs: {d}", flush=True)
        else:
            _log(f"rewrote {d}")
    if check:
        _log(f"check: {len(outputs.differences)} output(s) differ beyond the tolerances"
             if outputs.differences else "check: every output agrees with the files there")
    if failed:
        _log("FAILED: " + ", ".join(f"{s.example.title} ({s.result.method})" for s in failed))
        return 1
    return 1 if check and outputs.differences else 0
