"""The generated code of the mechanisms and of the integrator: the Python and C emitters.

Python (:data:`~nonholo.codegen.python_config.PYTHON`, the modules numba compiles):

- :func:`mechanism_files`: the mechanisms' modules, derived with SymPy (``derivations``,
  imported when asked for);
- :func:`python_kernels`: :mod:`nonholo.generated.cf4_kernels`, the integrator's kernels
  with the step expanded in place (:mod:`nonholo.codegen.inline`).

C (:data:`~nonholo.codegen.c_config.C`): :func:`kernel_source` assembles, for the generated
module of a mechanism, one C extension module holding the kernels of each of its systems
(:mod:`nonholo.integrate.system_kernels`): the physical ``G(R, q) u`` and, where the mechanism has
one, the desingularised frame ``N(R, q) w``. Every function in it is translated by
:mod:`nonholo.codegen.c_translation` from the Python that numba compiles — the generated
fields (``G_into``, ``QG_into``, ``delta``, …), the inlined kernels of
:mod:`nonholo.generated.cf4_kernels` and the helpers they call — with the system's names
and layout (``field_into``, ``D``, ``ROTATION``, …) bound as
:func:`nonholo.integrate.system_kernels.compile_system` binds them. The kernels are exported as
``<kernel>__<system>`` (``forward__physical``, ``forward_variational__frame``, …).
:func:`native_files` gives the catalog's sources, which ``nonholo derive`` writes to
``nonholo/generated/native/`` (built by ``pip install``);
:func:`nonholo.codegen.build.native_kernels` loads a mechanism's module (installed, cached
on disk, or compiled now).

The integrator passes its own pieces — its source, the functions translated besides the
inlined kernels and the helpers they call (``parts``) — so that code generation imports
nothing above it.
"""
from __future__ import annotations

import ast
import functools
import sys
import types
from pathlib import Path

from ..generated import cf4_kernels as inlined
from . import inline
from .c_config import C
from .c_extension import extension_source, translator_sources
from .c_subset import Function
from .cache import digest
from .python_config import PYTHON

#: The integrator's functions whose calls are expanded in place (:func:`python_kernels`).
INLINED = ("cf4_step", "cf4_stage", "cf4_close", "zpredict", "advance", "extremal_stage", "dexp_inverse")
#: The kernels written with them.
KERNELS = ("forward", "forward_variational", "frame_inputs", "extremal")
#: Argument kinds of the translated functions (see :data:`nonholo.codegen.c_subset.KINDS`):
#: the helpers (``parts``), the integrator's pieces and its kernels.
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
    "extremal": {"R0": "f8[2]", "q0": "f8[1]", "p0": "f8[1]", "h": "f8", "sgn": "f8", "delta_stop": "f8",
                 "Rs": "f8[3]", "Qs": "f8[2]", "Ps": "f8[2]", "U": "f8[3]"},
}
#: The kernels a :class:`~nonholo.integrate.system_kernels.Kernels` holds.
EXPORTED = ("forward", "forward_variational", "frame_inputs", "extremal")


def mechanism_files() -> dict[str, str]:
    """The mechanisms' generated modules (:func:`derivations.codegen.generated_files`).

    Returns
    -------
    dict of str to str
        File name → source, ``__init__.py`` (with ``MECHANISMS``) included.
    """
    from derivations import codegen  # SymPy: imported only when asked for

    return codegen.generated_files()


def python_kernels(sources: dict[str, str]) -> str:
    """The source of ``nonholo/generated/cf4_kernels.py``: the integrator's :data:`KERNELS`
    with every call of the functions in :data:`INLINED` expanded in place.

    Parameters
    ----------
    sources : dict of str to str
        The integrator's modules that define them: file, relative to the repository (named
        in the header) → source.

    Returns
    -------
    str
        The module's source.
    """
    paths = ", ".join(sources)
    header = PYTHON.header("The CF4 kernels with the step inlined (see nonholo.integrate.system_kernels).",
                           "nonholo/codegen/inline.py", paths)
    return inline.inlined_module(tuple(sources.values()), INLINED, KERNELS, header)


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
        The integrator's own pieces (``rates``, ``zstage``, ``no_singularity``,
        ``step_workspace``) and the helpers of :data:`HELPER_KINDS`, by name, passed by it
        (:func:`nonholo.integrate.system_kernels.native_parts`).
    kernels_text : str, optional
        The inlined kernels' source (by default :mod:`nonholo.generated.cf4_kernels`').

    Returns
    -------
    list of Function
        The :class:`~nonholo.codegen.c_subset.Function` objects to translate.
    """
    text = module_text(module)
    kernels_text = kernels_text if kernels_text is not None else Path(inlined.__file__).read_text()
    helper_calls = {n: f"{C.helper_prefix}{n}" for n in HELPER_KINDS}
    out = [Function(parts[n], helper_calls[n], kinds, exported=False, calls={"rodrigues": helper_calls["rodrigues"]})
           for n, kinds in HELPER_KINDS.items()]
    for system in systems(module):
        frame = system == "frame"
        G, QG = ("N_into", "QN_into") if frame else (("GF_into" if getattr(module, "DRIFT", False) else "G_into"),
                                                     "QG_into")
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
                     "OFFSET": 3 if module.ORIENTATION else 0,
                     "DRIFT_COLUMNS": int(bool(getattr(module, "DRIFT", False)) and not frame)}
        for name in ("rates", "zstage"):
            out.append(Function(parts[name], f"{system}_{name}", KERNEL_KINDS[name], exported=False,
                                calls=calls, constants=constants))
            calls[name] = f"{system}_{name}"
        for name in EXPORTED:
            if (name == "frame_inputs" and not frame) or (name == "extremal" and frame):
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
        The integrator's own pieces and helpers (:func:`functions`).
    kernels_text : str, optional
        The inlined kernels' source (by default :mod:`nonholo.generated.cf4_kernels`').

    Returns
    -------
    str
        :func:`nonholo.codegen.cache.digest` of the generated module's source, the
        kernels', the modules defining ``parts``, the translator's and this module's.
    """
    kernels_text = kernels_text if kernels_text is not None else Path(inlined.__file__).read_text()
    defining = dict.fromkeys(sys.modules[f.__module__] for f in parts.values())
    texts = [module_text(module), kernels_text] + [Path(m.__file__).read_text() for m in defining]
    return digest(*texts, *translator_sources(), Path(__file__).read_text())


def kernel_source(module, parts: dict, kernels_text: str | None = None) -> str:
    """The C source of the native module of a generated module.

    Parameters
    ----------
    module : module
        The mechanism's generated module.
    parts : dict
        The integrator's own pieces and helpers (:func:`functions`).
    kernels_text : str, optional
        The inlined kernels' source (by default :mod:`nonholo.generated.cf4_kernels`').

    Returns
    -------
    str
        The C source.
    """
    header = C.header(f"Native CF4 kernels of the mechanism {module.NAME!r}",
                      "nonholo/codegen/emit.py, nonholo/codegen/c_translation.py",
                      "its generated module and nonholo/generated/cf4_kernels.py")
    return extension_source(C.module_name(module_name(module)), header, functions(module, parts, kernels_text),
                            source_digest(module, parts, kernels_text))


def native_files(files: dict[str, str], parts: dict) -> dict[str, str]:
    """The C sources of the mechanisms' native kernels, built by ``pip install``.

    Parameters
    ----------
    files : dict of str to str
        The generated modules, name → source: the mechanisms' (:func:`mechanism_files`) and
        ``cf4_kernels.py`` (:func:`python_kernels`).
    parts : dict
        The integrator's own pieces and helpers (:func:`functions`).

    Returns
    -------
    dict of str to str
        ``native/<mechanism>.c`` and ``native/__init__.py``, name → source.
    """
    out = {}
    for name in files["__init__.py"].split("MECHANISMS = ")[1].strip().strip("()").replace("'", "").split(","):
        name = name.strip()
        if not name:
            continue
        text = files[f"{name}.py"]
        module = types.ModuleType(PYTHON.module_name(name))
        exec(compile(text, f"nonholo/generated/{name}.py", "exec"), module.__dict__)
        module.SOURCE = text
        out[C.source_file(name)] = kernel_source(module, parts, files["cf4_kernels.py"])
    out[f"{C.directory}/__init__.py"] = ('"""Native kernels built by `pip install` from the C sources here '
                                        '(generated by `nonholo derive`; do not edit)."""\n')
    return out
