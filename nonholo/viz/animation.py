"""Every mechanism seen moving: :func:`animate` writes a GIF or an MP4 of a planned motion.

What is drawn depends on the mechanism (:func:`animation_kind`; the frames of each kind are
drawn by :mod:`nonholo.viz.animation_scenes`, and this module renders them to the file):

- ``"platform"`` -- a mechanism with legs and a disk (its ``geometry``): the
  platform in 3-D as :func:`~nonholo.viz.platform_drawing.draw_platform` draws it, with the
  path of its body z axis' tip and ``Δ`` (as :func:`~nonholo.viz.platform_animation.animate_platform`);
- ``"ball"`` -- an orientation and a position on the plane (the rolling ball): the ball in
  3-D on the plane with its body-fixed parallels, meridians and axes, and seen from above,
  its upper half's marks and its axes projected, with the contact path so far;
- ``"vehicle"`` -- a mechanism with a :class:`~nonholo.model.drawing.Drawing` (the car, the
  unicycle, a mechanism file's ``[drawing]``): its bodies and wheels on the plane, the path
  so far, and the goal's pose dashed;
- ``"state"`` -- anything else (Brockett's integrator, the attitude, a mechanism of one's
  own without a drawing): the body axes in 3-D for an orientation, else the path of the
  first two or three coordinates with a moving marker, beside the coordinates (the RPY
  angles without any) against time with a moving cursor.

Frames are equally spaced in time (orientations interpolated on SO(3), coordinates
linearly between the samples). A ``.gif`` is written by matplotlib's ``PillowWriter``, an
``.mp4`` by its ``FFMpegWriter`` with the ``ffmpeg`` of the ``imageio-ffmpeg`` package (or
one on the ``PATH``); the file is put in place as every file the package writes
(:mod:`nonholo.io.safe_write`). Long renders show a progress bar on stderr.
"""
from __future__ import annotations

import shutil
import sys
import tempfile
from collections.abc import Mapping
from pathlib import Path

import matplotlib

from ..io import safe_write
from ..model import catalog
from ..model.drawing import Drawing
from ..numerics.checks import check_count
from .animation_scenes import Motion, ball_scene, platform_scene, state_scene, vehicle_scene
from .platform_drawing import result_mechanism
from .quantities import plane_position
from .result_lines import has_trajectory
from .style import STYLE

#: The formats :func:`animate` writes, by suffix.
FORMATS = {".gif": "gif", ".mp4": "mp4"}
#: What an animation shows (see the module).
KINDS = ("platform", "ball", "vehicle", "state")
#: From this many frames on, a progress bar is shown unless ``progress=False``.
PROGRESS_FRAMES = 100
#: The largest number of frames, frame rate and resolution.
MAX_FRAMES, MAX_FPS, MAX_DPI = 10_000, 120, 600
#: How to install what an MP4 needs.
FFMPEG_HINT = "python -m pip install imageio-ffmpeg (or write a .gif)"


def output_format(path, argument: str = "path") -> str:
    """The format of an animation file, from its suffix.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    argument : str
        The name the error gives the path (``"--out"``).

    Returns
    -------
    str
        ``"gif"`` or ``"mp4"``.

    Raises
    ------
    ValueError
        Naming ``argument``, for another suffix.
    """
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise ValueError(f"{argument}: {str(path)!r} must end in {' or '.join(FORMATS)} "
                         f"(got {suffix or 'no suffix'})")
    return FORMATS[suffix]


def ffmpeg_executable() -> str:
    """The ``ffmpeg`` an MP4 is written with.

    Returns
    -------
    str
        The one the ``imageio-ffmpeg`` package ships, else one on the ``PATH``.

    Raises
    ------
    RuntimeError
        If there is none, saying to install ``imageio-ffmpeg`` or to write a ``.gif``.
    """
    try:
        import imageio_ffmpeg
    except ImportError:
        found = shutil.which("ffmpeg")
        if found:
            return found
        raise RuntimeError(f"writing an .mp4 needs ffmpeg, which is not installed: {FFMPEG_HINT}") from None
    try:
        return imageio_ffmpeg.get_ffmpeg_exe()
    except RuntimeError as exc:
        raise RuntimeError(f"writing an .mp4 needs ffmpeg ({exc}): {FFMPEG_HINT}") from None


def drawing_for(result, drawing=None):
    """The drawing a result's vehicle is drawn with.

    Parameters
    ----------
    result : PlanResult
        The plan.
    drawing : Drawing or mapping, optional
        A drawing, or its data (:meth:`~nonholo.model.drawing.Drawing.from_mapping`, in the
        mechanism's coordinates).

    Returns
    -------
    Drawing or None
        ``drawing``, else the mechanism's (its ``drawing``), else that of the
        catalog's mechanism of its name and coordinates; ``None`` without any.

    Raises
    ------
    ValueError
        For drawing data :meth:`~nonholo.model.drawing.Drawing.from_mapping` refuses, or a
        drawing of other coordinates than the mechanism's.
    """
    mech = result_mechanism(result)
    if isinstance(drawing, Mapping):
        drawing = Drawing.from_mapping(drawing, mech.coordinates, where="drawing")
    if drawing is not None:
        if not isinstance(drawing, Drawing):
            raise ValueError(f"drawing must be a nonholo.model.drawing.Drawing or its data, "
                             f"got {type(drawing).__name__}")
        if tuple(drawing.coordinates) != tuple(mech.coordinates):
            raise ValueError(f"drawing: drawn in the coordinates ({', '.join(drawing.coordinates)}), but "
                             f"mechanism {mech.name!r} has ({', '.join(mech.coordinates)})")
        return drawing
    if isinstance(mech.drawing, Drawing):
        return mech.drawing
    if mech.name in catalog.names():
        known = catalog.get(mech.name).drawing
        if isinstance(known, Drawing) and tuple(known.coordinates) == tuple(mech.coordinates):
            return known
    return None


def animation_kind(result, drawing=None, geometry=None) -> str:
    """What the animation of a result shows (see the module).

    Parameters
    ----------
    result : PlanResult
        The plan.
    drawing : Drawing or mapping, optional
        A drawing for a vehicle (:func:`drawing_for`).
    geometry : object, optional
        A platform geometry (as :func:`~nonholo.viz.platform_drawing.as_geometry` takes it).

    Returns
    -------
    str
        One of :data:`KINDS`.

    Raises
    ------
    ValueError
        If the result's mechanism is unknown (not in the catalog and not carried).
    """
    mech = result_mechanism(result)
    if mech is None:
        raise ValueError(f"result's mechanism {getattr(result, 'mechanism', None)!r} is not in the catalog "
                         "and the result does not carry it")
    if geometry is not None or mech.geometry is not None:
        return "platform"
    if drawing_for(result, drawing) is not None:
        return "vehicle"
    if mech.space.axes("rotation") and mech.n_coordinates == 2 and plane_position(mech) == (0, 1):
        return "ball"
    return "state"


def animate(result, path, *, frames: int = 60, fps: int = 20, dpi: int = 80, kind: str | None = None,
            drawing=None, geometry=None, view: dict | None = None, progress: bool | None = None) -> Path:
    """Write an animation of a planned motion, for any mechanism (see the module).

    Parameters
    ----------
    result : PlanResult
        The plan (made in this process or read by :meth:`~nonholo.io.result.PlanResult.load`: its
        ``kinematics`` is the mechanism).
    path : str or pathlib.Path
        The file, ``.gif`` or ``.mp4`` (its directory is created if needed).
    frames : int
        The number of frames (at most :data:`MAX_FRAMES`).
    fps : int
        Frames per second (at most :data:`MAX_FPS`).
    dpi : int
        The frames' resolution (at most :data:`MAX_DPI`).
    kind : str, optional
        What to show, one of :data:`KINDS` (default: :func:`animation_kind`).
    drawing : Drawing or mapping, optional
        A vehicle's drawing (default: the mechanism's, :func:`drawing_for`).
    geometry : object, optional
        A platform's geometry (default: the mechanism's).
    view : dict, optional
        Elevation and azimuth of a 3-D view (degrees), overriding the default.
    progress : bool, optional
        Show a progress bar on stderr (default: from :data:`PROGRESS_FRAMES` frames on).

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    ValueError
        Naming the argument: ``frames``, ``fps`` or ``dpi`` not a positive integer within
        its bound, ``path`` not a ``.gif`` or ``.mp4`` or not a file that can be written,
        ``kind`` not one of :data:`KINDS` or not one the mechanism can be drawn as, a
        result without a trajectory or of an unknown mechanism.
    RuntimeError
        For an ``.mp4`` without ``ffmpeg`` (:func:`ffmpeg_executable`).
    """
    frames = check_count(frames, "frames", 1, MAX_FRAMES)
    fps = check_count(fps, "fps", 1, MAX_FPS)
    dpi = check_count(dpi, "dpi", 1, MAX_DPI)
    fmt = output_format(path, "path")
    executable = ffmpeg_executable() if fmt == "mp4" else None
    path = Path(path)
    if not has_trajectory(result):
        raise ValueError("result has no trajectory to animate")
    chosen = animation_kind(result, drawing, geometry)
    if kind is None:
        kind = chosen
    elif kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    elif kind != chosen and kind != "state":
        raise ValueError(f"kind: mechanism {result_mechanism(result).name!r} is drawn as {chosen!r} "
                         f"(or 'state'), not {kind!r}")
    safe_write.check_target(path, "path")
    path.parent.mkdir(parents=True, exist_ok=True)
    motion = Motion(result, frames)
    show = frames >= PROGRESS_FRAMES if progress is None else bool(progress)
    with matplotlib.rc_context(STYLE):
        if kind == "platform":
            fig, draw = platform_scene(result, motion, geometry, view)
        elif kind == "ball":
            fig, draw = ball_scene(result, motion, view)
        elif kind == "vehicle":
            fig, draw = vehicle_scene(result, motion, drawing_for(result, drawing))
        else:
            fig, draw = state_scene(result, motion, view)
        data = _render(fig, draw, frames, fmt, fps, dpi, executable, show, path.name)
    return safe_write.write_bytes(path, data, "path")


def _render(fig, draw, frames: int, fmt: str, fps: int, dpi: int, executable, show: bool, name: str) -> bytes:
    """The animation's bytes: ``draw(k)`` then a grab of ``fig``, for every frame."""
    from matplotlib.animation import FFMpegWriter, PillowWriter
    from tqdm import tqdm

    rc = {}
    if fmt == "mp4":
        rc["animation.ffmpeg_path"] = executable
        # yuv420p (what players take) needs an even width and height
        writer = FFMpegWriter(fps=fps, codec="h264",
                              extra_args=["-pix_fmt", "yuv420p", "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2"])
    else:
        writer = PillowWriter(fps=fps)
    with tempfile.TemporaryDirectory(prefix="nonholo-animation-") as folder, matplotlib.rc_context(rc):
        out = Path(folder) / f"animation.{fmt}"
        with tqdm(total=frames, desc=f"animating {name}", unit="frame", file=sys.stderr,
                  disable=not show, dynamic_ncols=True) as bar:
            # the layout is made once, on the first frame, and kept: frames neither jump
            # nor pay for it again
            draw(0)
            fig.draw_without_rendering()
            fig.set_layout_engine(None)
            with writer.saving(fig, str(out), dpi):
                for k in range(frames):
                    draw(k)
                    writer.grab_frame()
                    bar.update()
        return out.read_bytes()
