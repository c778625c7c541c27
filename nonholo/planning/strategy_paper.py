"""Strategy ``"paper"``: the appendix's algorithm (Tchoń & Jakubiak, eqs. (4)–(11)).

Euler steps of the θ-flow (11), then Newton steps, with the step control of
:func:`nonholo.planning.core.descend`, in the physical inputs ``u``:

- parametric form (Fourier coefficients ``λ``, :class:`~nonholo.controls.parametrisations.Fourier`):
  ``dλ/dθ = −γ J^# l_T`` with ``J = ∫ Φ(T,t) B(t) P(t) dt`` (3 × m(2K+1)) and ``J^#`` the
  Euclidean Moore–Penrose pseudo-inverse;
- nonparametric form (values ``v_j`` on a grid, :class:`~nonholo.controls.parametrisations.PiecewiseConstant`):
  the pseudo-inverse in the L2 metric of the controls, ``∫|u'|² dt = Σ h_j |u'_j|²``:
  ``u'_j = −γ G_jᵀ M_d^{-1} l_T / h_j`` with ``G_j = ∫_{I_j} Φ(T,t) B(t) dt`` and
  ``M_d = Σ_j G_j G_jᵀ / h_j`` — the grid version of
  ``u'(t) = −γ Bᵀ(t) Φᵀ(T,t) M(T)^{-1} l_T`` (11), to which it converges as the grid is
  refined (``M_d → M(T)``).

(For the platform the Euclidean and the L2 metric give the same Fourier steps: the mean
inputs alone fix ``r11(T)``, ``r22(T)`` — ``u1 = −ṙ22/2``, ``u2 = −ṙ11/2`` — so the
oscillating columns of ``J`` have rank 1, and both metrics weigh all oscillating
coefficients alike.)
"""
from __future__ import annotations

from ..motion.simulation import DELTA_STOP
from ..numerics import kernels
from .core import Outcome, Strategy, descend, record, step_scale


class PaperStrategy(Strategy):
    """The appendix's algorithm: Euler steps of the θ-flow (11), then Newton steps.

    Parameters
    ----------
    options : Options
        The run's settings.
    """

    name = "paper"

    def solve(self, endpoint, start, callback=None):
        """Plan from ``start`` in the physical inputs, with the minimum-norm step ``J^#``.

        Parameters
        ----------
        endpoint : EndpointMap
            The endpoint.
        start : Start
            The initial control.
        callback : callable, optional
            Called as ``callback(record)`` per accepted step; a true value stops the run.

        Returns
        -------
        Outcome
            The run's outcome.
        """
        opt = self.options
        ev = endpoint.evaluate(start.controls, delta_stop=DELTA_STOP)
        if not endpoint.admissible(ev):
            return Outcome(ev, False, f"the initial control is not admissible: {endpoint.why_not(ev)}; "
                           "choose another initial control (u0)")
        history = [record(0, ev, 0.0, "initial", 0)]
        if callback is not None and callback(history[-1]):
            return Outcome(ev, False, "stopped by callback", history, 0, stopped=True)
        scale = step_scale(endpoint, start.controls)
        d = descend(endpoint, ev, opt, lambda ev, newton: kernels.min_norm_step(ev.J, ev.l, scale),
                    budget=opt.max_iter, history=history, callback=callback)
        reason = f"max_iter = {opt.max_iter} reached with {d.reason}" if d.status == "budget" else d.reason
        return Outcome(d.evaluation, d.status == "converged", reason, history, d.steps,
                       stopped=d.status == "stopped")
