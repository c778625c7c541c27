"""The integrator and a mechanism: its systems' kernels compiled and bound once per
mechanism (:func:`compiled_system`), and the code ``nonholo derive`` generates for them
(:func:`kernels_module`, :func:`generated_files`).

A :class:`~nonholo.model.mechanism.Mechanism` is data (its generated module's functions);
the integrator (:mod:`nonholo.integrate.system_kernels`) compiles them into kernels,
natively where it can (:mod:`nonholo.codegen.build`), else with numba. Code generation
(:mod:`nonholo.codegen`) is given the integrator's pieces here.
"""
from __future__ import annotations

from pathlib import Path

from ..numerics import kernels
from . import system_kernels

#: The integrator's files the inlined kernels are generated from (the step's and the
#: kernels'), relative to the repository (named in the generated header).
KERNEL_SOURCES = ("nonholo/integrate/cf4.py", "nonholo/integrate/motion_kernels.py",
                  "nonholo/integrate/variational_kernels.py", "nonholo/integrate/extremal_kernels.py")


def compiled_system(mechanism, frame: bool = False) -> system_kernels.Kernels:
    """The compiled integrator kernels of a mechanism's system (see
    :func:`nonholo.integrate.system_kernels.compile_system`).

    Parameters
    ----------
    mechanism : nonholo.model.mechanism.Mechanism
        The mechanism.
    frame : bool
        ``False``: of ``(ω, q̇) = G(R, q) u``; ``True``: of the desingularised
        ``N(R, q) w``.

    Returns
    -------
    nonholo.integrate.system_kernels.Kernels
        The kernels, compiled once per mechanism and process (native or numba; kept by
        the mechanism's generated module).

    Raises
    ------
    ValueError
        If ``frame`` is asked of a mechanism without a desingularised frame.
    """
    if frame and not mechanism.has_frame:
        raise ValueError(f"mechanism {mechanism.name!r} has no desingularised frame N(R)")
    return system_kernels.compile_system(mechanism.module, frame)


def kernels_module() -> str:
    """The source of ``nonholo/generated/cf4_kernels.py``.

    Returns
    -------
    str
        The kernels of :data:`KERNEL_SOURCES` with the step expanded in place
        (:func:`nonholo.codegen.emit.python_kernels`).
    """
    from ..codegen import emit      # code generation: loaded by `nonholo derive` only

    here = Path(__file__).parent
    return emit.python_kernels({path: (here / Path(path).name).read_text() for path in KERNEL_SOURCES})


def generated_files() -> dict[str, str]:
    """What ``nonholo derive`` writes into ``nonholo/generated``.

    Returns
    -------
    dict of str to str
        File name → source: the mechanisms' modules (:func:`nonholo.codegen.emit.mechanism_files`,
        SymPy: imported when asked for), the inlined kernels (:func:`kernels_module`), the
        C of the mechanisms' native kernels (:func:`nonholo.codegen.emit.native_files`) and
        of the small numerics (:func:`nonholo.numerics.kernels.native_source`).
    """
    from ..codegen import emit
    from ..codegen.c_config import C

    files = {**emit.mechanism_files(), "cf4_kernels.py": kernels_module()}
    return {**files, **emit.native_files(files, system_kernels.native_parts()), C.source_file("numerics"): kernels.native_source()}
