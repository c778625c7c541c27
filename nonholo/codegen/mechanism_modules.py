"""The generated modules of mechanisms defined in a process (from equations, constraints or
a symbolic mechanism), as ``nonholo derive`` would write them.

The source is derived and generated with SymPy (``derivations``, imported only when asked
for), kept in the cache by a digest of the definition and of the generator
(:func:`nonholo.codegen.cache.cached_source`, verified before it is used), so that a later
run neither derives nor generates, and loaded as a module (:func:`load_source`: not
imported, it is not in the package).
"""
from __future__ import annotations

import hashlib
import types

from .cache import cached_source
from .python_config import PYTHON

#: The fields of a symbolic mechanism that define its generated module.
DEFINING_FIELDS = ("name", "description", "L", "delta", "inputs", "frame", "frame_inputs",
                   "coordinates", "units", "angles", "X")


def definition_digest(mechanism) -> str:
    """SHA-256 of a symbolic mechanism's definition and of the generator's version
    (``derivations.generator.generator_version``).

    Parameters
    ----------
    mechanism : derivations.mechanisms.Mechanism
        The symbolic mechanism; its :data:`DEFINING_FIELDS` are hashed as SymPy ``srepr``.

    Returns
    -------
    str
        The hex digest.
    """
    import sympy

    from derivations import generator

    h = hashlib.sha256(generator.generator_version().encode())
    for name in DEFINING_FIELDS:
        h.update(f"{name}={sympy.srepr(getattr(mechanism, name, None))};".encode())
    return h.hexdigest()


def generated_source(mechanism, cache: bool = True) -> str:
    """The generated module's source of a symbolic mechanism (``derivations.codegen``).

    Parameters
    ----------
    mechanism : derivations.mechanisms.Mechanism
        The symbolic mechanism.
    cache : bool
        Read the source from (or write it to) ``<cache>/generated/<name>_<digest>.py``
        (:func:`nonholo.codegen.cache.cached_source`, written atomically).

    Returns
    -------
    str
        The module's source.
    """
    from derivations import codegen  # SymPy: imported only when asked for

    if not cache:
        return codegen.mechanism_module(mechanism)
    return cached_source(mechanism.name, definition_digest(mechanism),
                         lambda: codegen.mechanism_module(mechanism))


def equations_source(form: str, name, arguments: dict, cache: bool = True) -> str:
    """The generated module's source of the mechanism ``derivations.equations.<form>(name,
    **arguments)`` builds.

    Parameters
    ----------
    form : str
        ``"field_mechanism"`` or ``"constraint_mechanism"``.
    name : str
        The mechanism's name.
    arguments : dict
        The keyword arguments of ``form``.
    cache : bool
        Cache the source (:func:`nonholo.codegen.cache.cached_source`) by a digest of the
        equations as given and the generator's version (:mod:`derivations.generator`), so a
        cached mechanism is neither derived nor generated again.

    Returns
    -------
    str
        The module's source.
    """
    from derivations import equations, generator

    # checked and converted before anything is hashed or derived: the name, text parsed,
    # the constants, the size budget (derivations.budget)
    arguments = equations.admitted(form, name, arguments)

    def build() -> str:
        from derivations import codegen

        return codegen.mechanism_module(getattr(equations, form)(name, **arguments))

    if not cache:
        return build()
    text = generator.definition_text(form, name, arguments)
    key = hashlib.sha256((generator.generator_version() + text).encode()).hexdigest()
    return cached_source(name, key, build)


def load_source(source: str, name: str) -> types.ModuleType:
    """A generated module's source loaded as a module (not imported: it is not on disk in
    the package).

    Parameters
    ----------
    source : str
        The source.
    name : str
        The mechanism's name (for the module's name and tracebacks).

    Returns
    -------
    module
        The module; its text is kept as ``SOURCE``.
    """
    module = types.ModuleType(PYTHON.module_name(name, memory=True))
    module.SOURCE = source
    exec(compile(source, f"<generated module of mechanism {name!r}>", "exec"), module.__dict__)
    return module


def symbolic_module(mechanism, cache: bool = True) -> types.ModuleType:
    """The generated module of a symbolic mechanism, loaded (:func:`generated_source`,
    :func:`load_source`).

    Parameters
    ----------
    mechanism : derivations.mechanisms.Mechanism
        The symbolic mechanism, checked first
        (:func:`derivations.mechanisms.check_definition`).
    cache : bool
        As for :func:`generated_source`.

    Returns
    -------
    module
        The module.

    Raises
    ------
    ValueError
        Naming the field, for a definition that
        :func:`derivations.mechanisms.check_definition` refuses (checked before anything is
        hashed or generated).
    """
    from derivations import mechanisms  # SymPy: imported only when asked for

    mechanisms.check_definition(mechanism)
    return load_source(generated_source(mechanism, cache), mechanism.name)


def equations_module(form: str, name, arguments: dict, cache: bool = True) -> types.ModuleType:
    """The generated module of a mechanism given by equations, loaded
    (:func:`equations_source`, :func:`load_source`).

    Parameters
    ----------
    form : str
        ``"field_mechanism"`` or ``"constraint_mechanism"``.
    name : str
        The mechanism's name.
    arguments : dict
        The keyword arguments of ``form``.
    cache : bool
        As for :func:`equations_source`.

    Returns
    -------
    module
        The module.

    Raises
    ------
    ValueError
        Naming it, for equations :mod:`derivations.equations` refuses.
    """
    source = equations_source(form, name, arguments, cache)
    return load_source(source, name)
