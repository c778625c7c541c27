"""The integrator's kernels compiled per system: :func:`compile_system` binds a
mechanism's generated functions and layout into the kernels and picks the backend —
native (C translated from the same kernels, :mod:`nonholo.codegen.build`) where it can,
else numba.

The kernels (:mod:`nonholo.integrate.motion_kernels`,
:mod:`nonholo.integrate.variational_kernels`) and the step they take
(:mod:`nonholo.integrate.cf4`) call the system through four names — ``field_into``,
``field_derivative_into``, ``delta`` and (frame systems) ``W_into`` — and read the state's
layout from three constants — ``ROTATION`` (whether there is an orientation), ``D``
(``d``) and ``OFFSET`` (the row of ``q̇``'s first rate in ``G``: 3 with orientation, else
0) — defined in :mod:`nonholo.integrate.cf4` as placeholders. :func:`compile_system`
makes, per system, a copy of each kernel whose globals bind those names to the
mechanism's generated functions (``G_into``/``QG_into`` or ``N_into``/``QN_into``,
``delta``, ``W_into``, compiled with ``numba.njit``) and its layout, so that the functions
are inlined and the branches of a state without orientation (or without coordinates)
compile away; each copy has its own qualified name (mechanism, system, a hash of the
generated source), hence its own on-disk cache entry. (A closure over the compiled
functions would read the same, but numba cannot cache it: the cache key pickles the
closure's cells, and a compiled function pickles differently in every process.)

The step is inlined too, by code generation: called, it keeps its arrays out of
registers and slows every kernel markedly, and numba's own inlining multiplies the
compilation time. ``nonholo derive`` writes :mod:`nonholo.generated.cf4_kernels`, the
kernels with every call of the functions listed in :data:`nonholo.codegen.emit.INLINED`
expanded in place (:mod:`nonholo.codegen.inline`); that is what gets compiled.
``compile_system(..., inlined=False)`` compiles the kernels as written, and
``tests/integrate/test_cf4.py`` checks that both give the same numbers, bit for bit.
"""
from __future__ import annotations

import hashlib
import inspect
import sys
import types
from dataclasses import dataclass

import numpy as np

from ..generated import cf4_kernels as kernels_inlined
from ..numerics import effort
from ..numerics.jit import jit
from ..numerics.kernels import exp_times, inv33, inverse_into, rodrigues
from . import cf4, extremal_kernels, motion_kernels, variational_kernels

@dataclass(frozen=True)
class Kernels:
    """The compiled kernels of one system of a mechanism: ``(ω, q̇) = G(R, q) u`` or, with
    ``frame``, its desingularised field ``N(R, q) w`` (then :attr:`frame_inputs` evaluates
    ``u = W(R, q) w``). Arguments: those of the functions of the same names.

    Parameters
    ----------
    name : str
        The mechanism's name.
    frame : bool
        Whether the system is the frame's.
    n_inputs : int
        ``m``.
    forward, forward_variational : callable
        The kernels :func:`~nonholo.integrate.motion_kernels.forward` and
        :func:`~nonholo.integrate.variational_kernels.forward_variational`.
    frame_inputs : callable or None
        The kernel :func:`~nonholo.integrate.motion_kernels.frame_inputs` (frame systems).
    extremal : callable or None
        The kernel :func:`~nonholo.integrate.extremal_kernels.extremal` (physical systems).
    n_coordinates : int, default 0
        ``k``, the number of coordinates ``q`` of the state (0 on SO(3)).
    backend : str, default "numba"
        ``"native"`` (C translated from these kernels,
        :mod:`nonholo.codegen.emit`) or ``"numba"``.
    """

    name: str
    frame: bool
    n_inputs: int
    forward: object
    forward_variational: object
    frame_inputs: object = None
    extremal: object = None
    #: ``k``, the number of coordinates ``q`` of the state (0 on SO(3))
    n_coordinates: int = 0
    #: ``"native"`` (C translated from these kernels, :mod:`nonholo.codegen.emit`)
    #: or ``"numba"``
    backend: str = "numba"

    def nodes(self, steps: int) -> tuple[np.ndarray, np.ndarray]:
        """Node arrays for a kernel's trajectory.

        Parameters
        ----------
        steps : int
            The steps.

        Returns
        -------
        Rs : numpy.ndarray
            ``(steps+1, 3, 3)``, uninitialised.
        Qs : numpy.ndarray
            ``(steps+1, k)``, uninitialised.
        """
        return np.empty((steps + 1, 3, 3)), np.empty((steps + 1, self.n_coordinates))


#: The kernels, in the form numba compiles: :mod:`nonholo.generated.cf4_kernels`, the
#: kernels with the calls of the step and its parts expanded in place (written by
#: ``nonholo derive``, see :mod:`nonholo.codegen.inline`); the helpers they still call,
#: specialised first.
_TEMPLATES = (cf4.rates, variational_kernels.zstage, kernels_inlined.forward,
              kernels_inlined.forward_variational, kernels_inlined.frame_inputs, kernels_inlined.extremal)
#: The kernels as written (``compile_system(..., inlined=False)``).
_WRITTEN = (cf4.rates, cf4.advance, variational_kernels.zpredict, cf4.cf4_stage, cf4.cf4_step,
            variational_kernels.zstage, motion_kernels.forward, variational_kernels.forward_variational,
            motion_kernels.frame_inputs, extremal_kernels.extremal_stage, extremal_kernels.dexp_inverse,
            extremal_kernels.extremal)
#: The globals of every kernel's copy before the system's names are bound (:func:`specialise`):
#: those of the modules that write the kernels and the step (the step's module last: its
#: name is the copies' module).
_KERNEL_GLOBALS = {**vars(motion_kernels), **vars(variational_kernels), **vars(extremal_kernels), **vars(cf4)}


def specialise(template, namespace: dict, bindings: dict, tag: str, cache: bool):
    """A compiled copy of a kernel with the system's names bound.

    Parameters
    ----------
    template : function
        The kernel.
    namespace : dict
        The kernels' globals: those of the modules that write them.
    bindings : dict
        The system's names.
    tag : str
        The system's tag (:func:`system_tag`): the copy's own cache entry.
    cache : bool
        Whether numba caches it on disk.

    Returns
    -------
    numba.core.registry.CPUDispatcher
        The compiled copy.
    """
    f = types.FunctionType(template.__code__, {**namespace, **bindings}, template.__name__)
    f.__qualname__ = f"{template.__name__}__{tag}"        # its own cache entry
    f.__module__ = namespace["__name__"]
    f.__doc__ = template.__doc__
    return jit(f, cache=cache, lazy=False)


def system_tag(module, frame: bool) -> str:
    """The cache name of a system: mechanism, system and a hash of the generated source.

    Parameters
    ----------
    module : module
        The mechanism's generated module.
    frame : bool
        Whether the system is the frame's.

    Returns
    -------
    str
        The tag.
    """
    src = inspect.getsource(module) if importable(module) else module.SOURCE
    return f"{module.NAME}{'_frame' if frame else ''}_{hashlib.sha256(src.encode()).hexdigest()[:12]}"


def importable(module) -> bool:
    """Whether a module can be re-imported by name (a cached kernel refers to it by name).

    Parameters
    ----------
    module : module
        A generated module.

    Returns
    -------
    bool
        Whether ``sys.modules`` holds it under its name.
    """
    return sys.modules.get(getattr(module, "__name__", None)) is module


#: Compiled kernels by system tag, and by (module, frame) (the tag hashes the source).
_COMPILED: dict[str, Kernels] = {}
_BY_MODULE: dict[tuple, Kernels] = {}


def compile_system(module, frame: bool = False, inlined: bool = True, fast_derivative: bool = True,
                   backend: str | None = None) -> Kernels:
    """The kernels of a system of the generated ``module``'s mechanism (compiled once,
    cached on disk).

    ``frame=False``: ``(ω, q̇) = G(R, q) u`` (``G_into``, ``QG_into``); ``frame=True``: the
    desingularised field ``N(R, q) w`` (``N_into``, ``QN_into``, and ``W_into`` for
    :func:`~nonholo.integrate.motion_kernels.frame_inputs`). Both watch the mechanism's
    ``delta`` (if any). Every kernel takes the state as ``(R0, q0)`` (see
    :func:`~nonholo.integrate.motion_kernels.forward`). Kernels of a
    module that cannot be re-imported by name (built in this process, see
    :meth:`nonholo.model.mechanism.Mechanism.from_symbolic`) are not cached on disk. Numba
    compiles a kernel on its first call, so a run pays only for what it uses.
    ``inlined=False`` compiles the kernels as their modules write them instead (the step
    called, not inlined; slower, not cached): the reference the generated ones are
    checked against. ``fast_derivative=False`` compiles ``QG`` without fast-math (not
    cached): LLVM may then reorder its arithmetic differently wherever it is inlined, so
    only these kernels are bit for bit the same in both forms.

    Parameters
    ----------
    module : module
        The mechanism's generated module.
    frame : bool, default False
        Whether to compile the frame system.
    inlined : bool, default True
        Whether to compile the inlined kernels.
    fast_derivative : bool, default True
        Whether to compile ``QG`` with fast-math.
    backend : str, optional
        ``"native"`` — the same kernels translated to C and compiled ahead of time
        (:mod:`nonholo.codegen.emit`) — or ``"numba"``; by default native where
        available (a C compiler, ``NONHOLO_BACKEND`` not ``numba``), else numba.

    Returns
    -------
    Kernels
        The kernels.

    Raises
    ------
    ValueError
        For an unknown ``backend``, or ``frame`` for a mechanism without a frame.
    RuntimeError
        If ``backend="native"`` and native kernels are unavailable.
    """
    if backend not in (None, "native", "numba"):
        raise ValueError(f"backend must be 'native', 'numba' or None, not {backend!r}")
    if frame and not getattr(module, "HAS_FRAME", False):
        raise ValueError(f"mechanism {module.NAME!r} has no desingularised frame N(R, q)")
    if backend != "numba" and inlined and fast_derivative:
        kern = _native(module, frame, required=backend == "native")
        if kern is not None:
            return kern
    if (module, frame) in _BY_MODULE and inlined and fast_derivative:
        return _BY_MODULE[module, frame]
    if not (inlined and fast_derivative):
        tag = system_tag(module, frame) + ("" if inlined else "_written") + ("" if fast_derivative else "_exact")
        return _compile(module, frame, _TEMPLATES if inlined else _WRITTEN, tag, False, fast_derivative)
    tag = system_tag(module, frame)
    if tag in _COMPILED:
        _BY_MODULE[module, frame] = _COMPILED[tag]
        return _COMPILED[tag]
    kern = _compile(module, frame, _TEMPLATES, tag, importable(module))
    _COMPILED[tag] = _BY_MODULE[module, frame] = kern
    return kern


_NATIVE: dict[tuple, Kernels] = {}


def native_parts() -> dict:
    """The functions the native kernels are translated from besides the inlined kernels:
    the integrator's pieces and the helpers they call.

    Returns
    -------
    dict
        ``rates``, ``zstage``, ``no_singularity``, ``step_workspace`` and the helpers
        ``rodrigues``, ``exp_times``, ``inv33``, ``inverse_into``
        (:mod:`nonholo.numerics.kernels`) by name (see
        :func:`nonholo.codegen.emit.functions`).
    """
    return {"rates": cf4.rates, "zstage": variational_kernels.zstage, "no_singularity": cf4.no_singularity,
            "step_workspace": cf4.step_workspace,
            "rodrigues": rodrigues, "exp_times": exp_times, "inv33": inv33, "inverse_into": inverse_into}


def _native(module, frame: bool, required: bool) -> Kernels | None:
    """The native kernels of a system (see :func:`compile_system`), or None."""
    from ..codegen import build      # the native build: loaded at the first compile

    if not build.enabled():
        if required:
            raise RuntimeError("native kernels asked for, but NONHOLO_BACKEND is 'numba'")
        return None
    if (module, frame) in _NATIVE:
        return _NATIVE[module, frame]
    fns = build.native_kernels(module, frame, native_parts())
    if fns is None:
        if required:
            raise RuntimeError(f"no native kernels for {module.NAME!r} (no C compiler, or NONHOLO_BACKEND=numba)")
        return None
    kern = Kernels(name=module.NAME, frame=frame, n_inputs=module.N_INPUTS,
                   n_coordinates=len(module.COORDINATES),
                   forward=metered(fns["forward"], effort.FORWARD_WEIGHT, 2),
                   forward_variational=metered(fns["forward_variational"], 1.0, 2),
                   frame_inputs=None if fns["frame_inputs"] is None
                   else metered(fns["frame_inputs"], effort.FORWARD_WEIGHT, 2),
                   extremal=None if fns["extremal"] is None else metered(fns["extremal"], effort.EXTREMAL_WEIGHT, 9),
                   backend="native")
    _NATIVE[module, frame] = kern
    return kern


def _compile(module, frame: bool, templates, tag: str, cache: bool, fast_derivative: bool = True) -> Kernels:
    """Compile ``templates`` for a system of ``module`` (see :func:`compile_system`)."""
    G, QG = (module.N_into, module.QN_into) if frame else (field_function(module), module.QG_into)
    bindings = {
        "field_into": jit(G, cache=False, lazy=False),
        # QG feeds only the variational system (the Jacobian): fast-math lets LLVM turn
        # its ``x**(-2.0)`` into a multiplication (the result changes at round-off level)
        "field_derivative_into": jit(QG, cache=False, lazy=False, fastmath=fast_derivative),
        "delta": jit(module.delta if module.HAS_SINGULAR_SET else cf4.no_singularity, cache=False, lazy=False),
        "ROTATION": bool(module.ORIENTATION),
        "D": (3 if module.ORIENTATION else 0) + len(module.COORDINATES),
        "OFFSET": 3 if module.ORIENTATION else 0,
        "DRIFT_COLUMNS": drift_columns(module, frame),
    }
    if frame:
        bindings["W_into"] = jit(module.W_into, cache=False, lazy=False)
    for template in templates:
        if (template.__name__ == "frame_inputs" and not frame) or (template.__name__ == "extremal" and frame):
            continue
        bindings[template.__name__] = specialise(template, _KERNEL_GLOBALS, bindings, tag, cache)
    frame_kernel = bindings.get("frame_inputs")
    kern = Kernels(name=module.NAME, frame=frame, n_inputs=module.N_INPUTS,
                   n_coordinates=len(module.COORDINATES),
                   forward=metered(bindings["forward"], effort.FORWARD_WEIGHT, 2),
                   forward_variational=metered(bindings["forward_variational"], 1.0, 2),
                   frame_inputs=None if frame_kernel is None else metered(frame_kernel, effort.FORWARD_WEIGHT, 2),
                   extremal=None if frame else metered(bindings["extremal"], effort.EXTREMAL_WEIGHT, 9))
    return kern


def drift_columns(module, frame: bool) -> int:
    """The field's columns past the inputs: 1 for the physical system of a mechanism with
    drift (:data:`nonholo.integrate.cf4.DRIFT_COLUMNS`), else 0.

    Parameters
    ----------
    module : module
        The mechanism's generated module.
    frame : bool
        Whether the system is the frame's.

    Returns
    -------
    int
        0 or 1.
    """
    return int(bool(getattr(module, "DRIFT", False)) and not frame)


def field_function(module):
    """The generated function the kernels call as ``field_into`` for the physical system:
    ``GF_into`` (``[G | f]``) with drift, else ``G_into``.

    Parameters
    ----------
    module : module
        The mechanism's generated module.

    Returns
    -------
    function
        The generated function.
    """
    return module.GF_into if drift_columns(module, False) else module.G_into


def metered(kernel, weight: float, counted: int):
    """A kernel counting its effort (:mod:`nonholo.numerics.effort`).

    Parameters
    ----------
    kernel : callable
        The kernel.
    weight : float
        Effort per element of the counted argument.
    counted : int
        The argument's position (the stage table's steps; ``frame_inputs``' node indices).

    Returns
    -------
    callable
        The kernel, counting (the kernel itself as its ``kernel`` attribute).
    """

    def run(*args):
        effort.add(weight * len(args[counted]))
        return kernel(*args)

    run.__name__ = run.__qualname__ = getattr(kernel, "__name__", "kernel")
    run.__doc__ = kernel.__doc__
    run.kernel = kernel
    return run
