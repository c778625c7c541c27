"""The CF4 kernels of a mechanism as C: translated from the same Python numba compiles.

:func:`kernel_source` assembles, for the generated module of a mechanism, one C extension
module holding the kernels of each of its systems (:mod:`nonholo.integrate.cf4`): the
physical ``G(R, q) u`` and, where the mechanism has one, the desingularised frame
``N(R, q) w``. Every function in it is translated by :mod:`nonholo.numerics.c_translation`
from the Python that numba compiles — the generated fields (``G_into``, ``QG_into``,
``delta``, …), the inlined kernels of :mod:`nonholo.generated.cf4_kernels` and the helpers
they call — with the system's names and layout (``field_into``, ``D``, ``ROTATION``, …)
bound as :func:`nonholo.integrate.cf4.compile_system` binds them. The kernels are exported
as ``<kernel>__<system>`` (``forward__physical``, ``forward_variational__frame``, …).

``nonholo derive`` writes the catalog's sources to ``nonholo/generated/native/`` (built by
``pip install``); :func:`native_kernels` loads a mechanism's module through
:func:`nonholo.numerics.native.load` (installed, cached on disk, or compiled now).
"""
from __future__ import annotations

import ast
import functools
import sys
from pathlib import Path

from ..generated import cf4_kernels as inlined
from ..numerics import kernels as small
from ..numerics import native
from ..numerics.c_translation import Function, extension_source

#: Argument kinds of the translated functions (see :data:`nonholo.numerics.c_translation.KINDS`).
FIELD_KINDS = {"R": "f8[2]", "q": "f8[1]", "v": "f8[1]", "u": "f8[1]", "out": "f8[2]"}
HELPER_KINDS = {
    "rodrigues": {"wx": "f8", "wy": "f8", "wz": "f8", "E": "f8[2]"},
    "exp_times": {"wx": "f8", "wy": "f8", "wz": "f8", "R": "f8[2]", "E": "f8[2]", "out": "f8[2]"},
    "inv33": {"Z": "f8[2]", "out": "f8[2]"},
    "inverse_into": {"A": "f8[2]", "out": "f8[2]"},
}
KERNEL_KINDS = {
    "rates": {"B": "f8[2]", "v": "f8[1]", "out": "f8[1]"},
    "zstage": {"Zc": "f8[2]", "Y": "f8[2]", "P": "f8[1]", "v": "f8[1]", "F": "f8[1]", "B": "f8[2]",
               "Qm": "f8[2]", "f": "f8[2]", "K": "f8[2]"},
    "forward": {"R0": "f8[2]", "q0": "f8[1]", "U": "f8[3]", "h": "f8", "sgn": "f8", "delta_stop": "f8",
                "Rs": "f8[3]", "Qs": "f8[2]"},
    "forward_variational": {"R0": "f8[2]", "q0": "f8[1]", "U": "f8[3]", "h": "f8", "sgn": "f8",
                            "delta_stop": "f8", "Bidx": "i8[3]", "Bval": "f8[3]", "stride_b": "i8",
                            "stride_i": "i8", "Rs": "f8[3]", "Qs": "f8[2]", "Zs": "f8[3]", "J": "f8[2]",
                            "Mq": "f8[2]", "Wd": "f8[2]", "full": "b1"},
    "frame_inputs": {"nodes": "f8[3]", "qnodes": "f8[2]", "idx": "i8[1]", "s": "f8[1]", "Wst": "f8[3]",
                     "w_end": "f8[2]", "Rout": "f8[3]", "Qout": "f8[2]", "out": "f8[2]"},
}
#: The kernels a :class:`~nonholo.integrate.cf4.Kernels` holds.
EXPORTED = ("forward", "forward_variational", "frame_inputs")


def module_name(module) -> str:
    """The native module's name (under ``nonholo.generated.native``) for a generated module.

    Parameters
    ----------
    module : module
        The mechanism's generated module.

    Returns
    -------
    str
        The mechanism's name.
    """
    return str(module.NAME)


def systems(module) -> list[str]:
    """The systems of a mechanism: ``physical`` and, if it has a frame, ``frame``.

    Parameters
    ----------
    module : module
        The mechanism's generated module.

    Returns
    -------
    list of str
        The systems' names.
    """
    return ["physical", "frame"] if getattr(module, "HAS_FRAME", False) else ["physical"]


def module_text(module) -> str:
    """The source of a generated module (its ``SOURCE`` if built in memory, else its file).

    Parameters
    ----------
    module : module
        The mechanism's generated module.

    Returns
    -------
    str
        The source.
    """
    return module.SOURCE if hasattr(module, "SOURCE") else Path(module.__file__).read_text()


def function_source(text: str, name: str) -> str:
    """The source of a top-level function in a module's source.

    Parameters
    ----------
    text : str
        The module's source.
    name : str
        The function's name.

    Returns
    -------
    str
        The function's source.

    Raises
    ------
    ValueError
        If there is no such function.
    """
    functions = _functions(text)
    if name not in functions:
        raise ValueError(f"no function {name!r} in the generated module")
    return functions[name]


@functools.lru_cache(maxsize=64)
def _functions(text: str) -> dict[str, str]:
    lines = text.splitlines(keepends=True)
    return {node.name: "".join(lines[node.lineno - 1:node.end_lineno])
            for node in ast.parse(text).body if isinstance(node, ast.FunctionDef)}


def functions(module, parts: dict, kernels_text: str | None = None) -> list:
    """The functions of the native module of a generated module, in translation order.

    Parameters
    ----------
    module : module
        The mechanism's generated module.
    parts : dict
        The kernels' own pieces of :mod:`nonholo.integrate.cf4` (``rates``, ``zstage``,
        ``no_singularity``, ``step_workspace``), passed by it.
    kernels_text : str, optional
        The inlined kernels' source (by default :mod:`nonholo.generated.cf4_kernels`').

    Returns
    -------
    list of Function
        The :class:`~nonholo.numerics.c_translation.Function` objects to translate.
    """
    text = module_text(module)
    kernels_text = kernels_text if kernels_text is not None else Path(inlined.__file__).read_text()
    helpers = [Function(getattr(small, n), f"nh_{n}", kinds, exported=False,
                        calls={"rodrigues": "nh_rodrigues"}) for n, kinds in HELPER_KINDS.items()]
    out = list(helpers)
    helper_calls = {n: f"nh_{n}" for n in HELPER_KINDS}
    for system in systems(module):
        frame = system == "frame"
        G, QG = ("N_into", "QN_into") if frame else ("G_into", "QG_into")
        fields = {"field_into": (G, {"R": "f8[2]", "q": "f8[1]", "out": "f8[2]"}),
                  "field_derivative_into": (QG, {"R": "f8[2]", "q": "f8[1]", "v": "f8[1]", "out": "f8[2]"})}
        if frame:
            fields["W_into"] = ("W_into", {"R": "f8[2]", "q": "f8[1]", "out": "f8[2]"})
        delta = function_source(text, "delta") if module.HAS_SINGULAR_SET else parts['no_singularity']
        out.append(Function(delta, f"{system}_delta", {"R": "f8[2]", "q": "f8[1]"}, exported=False))
        calls = dict(helper_calls, delta=f"{system}_delta", step_workspace=parts['step_workspace'])
        for bound, (name, kinds) in fields.items():
            out.append(Function(function_source(text, name), f"{system}_{name}", kinds, exported=False))
            calls[bound] = f"{system}_{name}"
        constants = {"ROTATION": bool(module.ORIENTATION),
                     "D": (3 if module.ORIENTATION else 0) + len(module.COORDINATES),
                     "OFFSET": 3 if module.ORIENTATION else 0}
        for name in ("rates", "zstage"):
            out.append(Function(parts[name], f"{system}_{name}", KERNEL_KINDS[name], exported=False,
                                calls=calls, constants=constants))
            calls[name] = f"{system}_{name}"
        for name in EXPORTED:
            if name == "frame_inputs" and not frame:
                continue
            out.append(Function(function_source(kernels_text, name), f"{name}__{system}", KERNEL_KINDS[name],
                                calls=calls, constants=constants))
    return out


def source_digest(module, parts: dict, kernels_text: str | None = None) -> str:
    """The digest of what the native module of a generated module is translated from.

    Parameters
    ----------
    module : module
        The mechanism's generated module.
    parts : dict
        The kernels' own pieces of :mod:`nonholo.integrate.cf4`.
    kernels_text : str, optional
        The inlined kernels' source (by default :mod:`nonholo.generated.cf4_kernels`').

    Returns
    -------
    str
        :func:`nonholo.numerics.native.digest` of the generated module's source, the
        kernels' and helpers' modules, and the translator's.
    """
    from ..numerics import c_translation

    cf4 = sys.modules[parts["rates"].__module__]
    kernels_text = kernels_text if kernels_text is not None else Path(inlined.__file__).read_text()
    texts = [module_text(module), kernels_text] + [Path(m.__file__).read_text()
                                                   for m in (cf4, small, c_translation, sys.modules[__name__])]
    return native.digest(*texts)


def kernel_source(module, parts: dict, kernels_text: str | None = None) -> str:
    """The C source of the native module of a generated module.

    Parameters
    ----------
    module : module
        The mechanism's generated module.
    parts : dict
        The kernels' own pieces of :mod:`nonholo.integrate.cf4`.
    kernels_text : str, optional
        The inlined kernels' source (by default :mod:`nonholo.generated.cf4_kernels`').

    Returns
    -------
    str
        The C source.
    """
    header = (f"Native CF4 kernels of the mechanism {module.NAME!r}. Generated by `nonholo derive` "
              f"(nonholo/integrate/native_kernels.py, nonholo/numerics/c_translation.py) from "
              f"its generated module and nonholo/generated/cf4_kernels.py. Do not edit.")
    return extension_source(f"nonholo.generated.native.{module_name(module)}", header, functions(module, parts, kernels_text),
                            source_digest(module, parts, kernels_text))


def native_kernels(module, frame: bool, parts: dict):
    """The native kernels of a system of a generated module.

    Parameters
    ----------
    module : module
        The mechanism's generated module.
    frame : bool
        Whether the system is the frame's.
    parts : dict
        The kernels' own pieces of :mod:`nonholo.integrate.cf4`.

    Returns
    -------
    dict or None
        ``{"forward": …, "forward_variational": …, "frame_inputs": …}``, or ``None`` where
        native kernels are unavailable (see :func:`nonholo.numerics.native.load`).
    """
    if not native.enabled():
        return None
    lib = native.load(module_name(module), source_digest(module, parts), lambda: kernel_source(module, parts))
    if lib is None:
        return None
    system = "frame" if frame else "physical"
    return {name: getattr(lib, f"{name}__{system}", None) for name in EXPORTED}
