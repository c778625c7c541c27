"""Figures of the mechanisms, their singular sets and planned motions, by job:

- :mod:`~nonholo.viz.style` -- the house style, colours, the figure class
  :class:`NotebookFigure` (displayed as an image in Jupyter) and :func:`save_figure`;
- :mod:`~nonholo.viz.quantities` -- names and units of a mechanism's coordinates and inputs,
  and a vehicle's plane position, read from its data;
- :mod:`~nonholo.viz.platform_drawing` -- the platform's geometry and 3D schematic;
- :mod:`~nonholo.viz.singular_set` -- the singular set ``Δ = 0`` and its normal form;
- :mod:`~nonholo.viz.result_lines` -- several plans on one axes told apart: labels, line
  styles, colours, one legend;
- :mod:`~nonholo.viz.convergence_figures` -- a planner's iterations (convergence, the
  closest approach to ``Δ = 0``);
- :mod:`~nonholo.viz.plan_figures` -- figures of plans along their time (controls, RPY,
  legs, ``Δ``, body axes, example overview);
- :mod:`~nonholo.viz.refinement_figures` -- one plan's refinements (global route, leg
  limits, motion quality);
- :mod:`~nonholo.viz.mechanism_cards` -- one mechanism at a glance;
- :mod:`~nonholo.viz.platform_animation` -- a GIF of the platform's motion;
- :mod:`~nonholo.viz.animation` -- a GIF or an MP4 of a motion of any mechanism
  (:func:`animate`), its frames drawn per kind of mechanism by
  :mod:`~nonholo.viz.animation_scenes`;
- :mod:`~nonholo.viz.plan_summary` -- one plan of any mechanism at a glance (what
  ``nonholo plan --plot`` writes), with a vehicle's path on the plane;
- :mod:`~nonholo.viz.state_figures` -- plans whose state goes beyond SO(3) (the ball, the
  car);
- :mod:`~nonholo.viz.execution_figures` -- a plan played on its physics model
  (:func:`nonholo.physics.execution.execute`): error per stage, tracking, the motion, slip.

The public functions are re-exported here: ``from nonholo import viz; viz.rpy_figure(res)``.
"""
from .animation import animate
from .convergence_figures import convergence_figure, newton_switch, plot_convergence, plot_min_delta
from .execution_figures import execution_figure
from .mechanism_cards import mechanism_card_figure
from .plan_figures import (
    body_axes_figure,
    controls_figure,
    delta_figure,
    example_overview_figure,
    leg_lengths_figure,
    plot_body_axes,
    plot_controls,
    plot_delta,
    plot_leg_lengths,
    plot_rpy,
    rpy_along,
    rpy_figure,
)
from .plan_summary import plan_figure, plot_plane_path
from .platform_animation import animate_platform
from .platform_drawing import (
    MECHANISM_VIEW,
    as_geometry,
    delta_along,
    draw_platform,
    leg_lengths,
    mechanism_figure,
)
from .singular_set import (
    delta_rpy,
    mechanism_delta_rpy,
    normal_form_figure,
    normal_form_image,
    normal_form_surface,
    singular_set_figure,
    singular_set_points,
    singular_slices_figure,
)
from .quantities import input_units, plane_position
from .refinement_figures import global_route_figure, leg_limits_figure, motion_quality_figure
from .state_figures import ball_figure, car_figure, least_time_figure
from .style import (
    NEGATIVE_COLOR,
    PAIR_COLORS,
    POSITIVE_COLOR,
    RESULT_COLORS,
    RESULT_STYLES,
    STYLE,
    TRIPLE_COLORS,
    NotebookFigure,
    save_figure,
)

__all__ = [
    "STYLE", "RESULT_STYLES", "RESULT_COLORS", "PAIR_COLORS", "TRIPLE_COLORS", "POSITIVE_COLOR",
    "NEGATIVE_COLOR", "NotebookFigure", "save_figure", "input_units", "plane_position",
    "MECHANISM_VIEW", "as_geometry", "leg_lengths", "delta_along", "draw_platform", "mechanism_figure",
    "delta_rpy", "mechanism_delta_rpy", "singular_set_points", "singular_set_figure",
    "singular_slices_figure", "normal_form_surface", "normal_form_image", "normal_form_figure",
    "newton_switch", "rpy_along", "plot_convergence", "plot_controls", "plot_rpy", "plot_leg_lengths",
    "plot_delta", "plot_body_axes", "plot_min_delta", "convergence_figure", "controls_figure",
    "rpy_figure", "leg_lengths_figure", "delta_figure", "body_axes_figure", "global_route_figure",
    "leg_limits_figure", "motion_quality_figure", "example_overview_figure",
    "mechanism_card_figure", "animate_platform", "animate", "plan_figure", "plot_plane_path",
    "ball_figure", "car_figure", "least_time_figure", "execution_figure",
]
