"""What identifies a generated module, cheaply (nothing but SymPy's core is imported): the
code generator's version and the canonical text of a definition. A cache of generated
modules keys on both (:mod:`nonholo.codegen.mechanism_modules`), so that a cached module is found
without importing the generator or deriving anything.
"""
from __future__ import annotations

import hashlib
from collections.abc import Mapping
from pathlib import Path

import sympy as sp

from .admission import check_name

#: The modules whose code decides the text of a generated module (with SymPy's version).
GENERATOR_MODULES = ("admission", "budget", "codegen", "equations", "mechanisms", "rotations", "state_space",
                     "variational")


def generator_version() -> str:
    """SHA-256 of SymPy's version and of the sources of :data:`GENERATOR_MODULES`: it changes
    whenever a generated module's text may."""
    h = hashlib.sha256(sp.__version__.encode())
    for name in GENERATOR_MODULES:
        h.update(Path(__file__).with_name(f"{name}.py").read_bytes())
    return h.hexdigest()


def definition_text(form: str, name, arguments: Mapping) -> str:
    """A canonical text of a definition: the form, the name and each argument as SymPy
    ``srepr`` (mappings by their keys' names); ``ValueError`` for a name that is not an
    identifier or an argument that is not SymPy data (naming it). Text is kept as its
    ``repr``, never converted (SymPy's ``sympify`` would evaluate it); the arguments are
    expected within the budget (:mod:`derivations.budget`; ``srepr`` recurses), as
    :func:`derivations.equations.admitted` leaves them."""
    def text(value, key):
        if isinstance(value, Mapping):
            items = sorted(((str(k), text(k, key), text(v, key)) for k, v in value.items()))
            return "{" + ", ".join(f"{k}: {v}" for _, k, v in items) + "}"
        if isinstance(value, (list, tuple, sp.MatrixBase)):
            return "[" + ", ".join(text(v, key) for v in value) + "]"
        if value is None or isinstance(value, (str, bool)):
            return repr(value)
        try:
            return sp.srepr(value if isinstance(value, sp.Basic) else sp.sympify(value, strict=True))
        except (sp.SympifyError, TypeError, ValueError):
            raise ValueError(f"{key}: {value!r} is not a SymPy expression or symbol") from None

    name = check_name(name)
    return f"{form}({name!r}; " + "; ".join(f"{k}={text(v, k)}" for k, v in sorted(arguments.items())) + ")"
