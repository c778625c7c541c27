"""Sphinx extension: the benchmark pages and the API reference's completeness.

- The reference's module pages: one page per subpackage (top layer first), listing its
  public modules as found on disk, written into ``docs/api/modules/`` (not kept in git), and
  a page of the package's surface, ``nonholo.__all__``; a new module gets its page.
- Benchmark results: one page per ``benchmarks/results/*.md``, written into
  ``docs/benchmarks/results/`` (not kept in git) as an include of the file, with the
  script's figure of the same name if there is one, so that the numbers stay those the
  scripts wrote and a new results file gets its page.
- Completeness: every public module of ``nonholo`` (``nonholo.generated`` aside), every
  public class and function defined in one (its ``__all__`` if it has one, else every name
  without a leading underscore) and every name of ``nonholo.__all__`` has a page; a missing
  one is a build warning.
- References: ``nonholo.plan`` and the other names of ``nonholo.__all__`` resolve to where
  they are defined; a short name (``as_geometry``) to the public object of that name
  nearest to the referring module in the package's tree, if one is nearest.
- Raises: a public function or method whose body raises an exception has a ``Raises``
  section (numpydoc's own checks cover ``Parameters`` and ``Returns``).
"""
from __future__ import annotations

import ast
import dataclasses
import importlib
import inspect
import os
import pkgutil
import re
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "benchmarks" / "results"
PAGES = ROOT / "docs" / "benchmarks" / "results"
API_PAGES = ROOT / "docs" / "api" / "modules"
PACKAGE = "nonholo"

#: The subpackages, top layer first (``tests/project/test_architecture.py`` holds the order), with
#: what each one does; one not named here is listed after them.
SUBPACKAGES = {
    "cli": "the command line ``nonholo``: argument parsing and one module per command",
    "paper": "the ARK 2014 paper end to end: its examples, the main job and the audit's numeric checks",
    "batch": "many plans at once: sweeps on local processes or Dask, atlases over a grid of goals",
    "dynobench": "Dynobench's instances and trajectories: reading them, planning them, writing and checking "
                 "trajectories",
    "viz": "figures of mechanisms, singular sets, planned motions and their executions",
    "physics": "plans played on MuJoCo models generated from the mechanisms' data, with touch-ups",
    "planning": "the planner: ``plan``, the problem, constraints, strategies, the certificate's use, "
                "the global route, least energy and re-timing",
    "io": "the plan result, the plan file's codec, CSV export, problem tables and safe writes",
    "certify": "the certificate of a plan, the plan file's checks and the independent re-simulation",
    "motion": "simulation, a plan's controls replayed, frame controls, re-timed and rest-to-rest controls",
    "integrate": "the CF4 integrator with the variational system, and a mechanism's kernels compiled "
                 "per mechanism",
    "model": "the numeric mechanism (data: its generated functions), the catalog, the legs' stroke, "
             "obstacles, the paper's platform and the table of names and units",
    "controls": "control parametrisations (Fourier, Legendre, piecewise constant), stage tables, stitched hops",
    "spaces": "state spaces (SO(3), Euclidean, their product), the singular set, numeric rotations",
    "numerics": "numba kernels, small compiled numerics (native where built), the effort clock, "
                "argument checks",
    "codegen": "code generation: Python and C emitters, the inliner, Python to C translation, the "
               "compiler and the verified caches, one configuration per backend",
}


def benchmark_pages(results: Path = RESULTS, pages: Path = PAGES) -> list[str]:
    """Write one page per results file; drop the pages of results files that are gone.

    Parameters
    ----------
    results : pathlib.Path
        The folder of the results files (``*.md``).
    pages : pathlib.Path
        The folder the pages are written to.

    Returns
    -------
    list of str
        The pages' names (the results files' stems), sorted.
    """
    pages.mkdir(parents=True, exist_ok=True)
    names = sorted(p.stem for p in results.glob("*.md"))
    for name in names:
        text = (f"```{{include}} ../../../benchmarks/results/{name}.md\n"
                ":relative-images:\n```\n")
        if (results / f"{name}.png").is_file():
            text += f"\n![{name}](../../../benchmarks/results/{name}.png)\n"
        page = pages / f"{name}.md"
        if not page.is_file() or page.read_text() != text:
            page.write_text(text)
    for page in pages.glob("*.md"):
        if page.stem not in names:
            page.unlink()
    return names


def api_pages(pages: Path = API_PAGES) -> list[str]:
    """Write the reference's pages: the package's surface, then one page per subpackage.

    Parameters
    ----------
    pages : pathlib.Path
        The folder the pages are written to (``docs/api/modules``).

    Returns
    -------
    list of str
        The pages' names, in the order of the reference.
    """
    pages.mkdir(parents=True, exist_ok=True)
    package = importlib.import_module(PACKAGE)
    surface = "\n".join(f"   ~{getattr(package, n).__module__}.{getattr(package, n).__qualname__}"
                        for n in package.__all__)
    texts = {"00_surface": (
        f"The package: ``{PACKAGE}``\n{'=' * (len(PACKAGE) + 17)}\n\n"
        f".. automodule:: {PACKAGE}\n\n"
        f"Its public names, ``{PACKAGE}.__all__`` (each documented in the module that defines it):\n\n"
        f".. py:currentmodule:: None\n\n"
        f".. autosummary::\n   :nosignatures:\n\n{surface}\n")}
    modules = public_modules()
    found = sorted({m.split(".")[1] for m in modules if m.count(".") >= 1})
    order = [s for s in SUBPACKAGES if s in found] + [s for s in found if s not in SUBPACKAGES]
    for i, sub in enumerate(order, 1):
        full = f"{PACKAGE}.{sub}"
        title = f"``{full}``"
        what = SUBPACKAGES.get(sub) or (importlib.import_module(full).__doc__ or "").strip().split("\n")[0]
        members = "\n".join(f"   {m}" for m in modules if m == full or m.startswith(full + "."))
        texts[f"{i:02d}_{sub}"] = (f"{title}\n{'=' * len(title)}\n\n{what[:1].upper() + what[1:]}.\n\n"
                                   f".. autosummary::\n   :toctree: ../generated\n   :nosignatures:\n\n"
                                   f"{members}\n")
    for name, text in texts.items():
        page = pages / f"{name}.rst"
        if not page.is_file() or page.read_text() != text:
            page.write_text(text)
    for page in pages.glob("*.rst"):
        if page.stem not in texts:
            page.unlink()
    return list(texts)


def public_modules(package: str = PACKAGE) -> list[str]:
    """The public modules of the package: no part private, ``generated`` and ``__main__`` aside.

    Parameters
    ----------
    package : str
        The package's name.

    Returns
    -------
    list of str
        Full module names, the package itself first.
    """
    root = importlib.import_module(package)
    out = [package]
    for info in pkgutil.walk_packages(root.__path__, package + "."):
        parts = info.name.split(".")
        if any(p.startswith("_") for p in parts) or "generated" in parts:
            continue
        out.append(info.name)
    return out


def public_objects(module_name: str) -> list[str]:
    """The public classes and functions a module defines, by full name.

    Parameters
    ----------
    module_name : str
        A module's full name.

    Returns
    -------
    list of str
        ``module.name`` of the classes and functions named in the module's ``__all__`` and
        defined in it, or, without ``__all__``, of those defined in it whose names do not
        start with an underscore.
    """
    module = importlib.import_module(module_name)
    names = getattr(module, "__all__", None)
    if names is None:
        names = [n for n in vars(module) if not n.startswith("_")]
    out = []
    for name in names:
        obj = getattr(module, name, None)
        if (inspect.isclass(obj) or inspect.isfunction(obj)) and obj.__module__ == module_name:
            out.append(f"{module_name}.{name}")
    return out


RAISES = re.compile(r"^Raises\n-+$", re.MULTILINE)


def aliases(package: str = PACKAGE) -> dict[str, str]:
    """``{"nonholo.plan": "nonholo.planning.api.plan", ...}`` for the package's public names.

    Parameters
    ----------
    package : str
        The package's name.

    Returns
    -------
    dict of str to str
        The name under the package for every name of its ``__all__``, mapped to the full
        name of the class or function where it is defined.
    """
    module = importlib.import_module(package)
    out = {}
    for name in module.__all__:
        obj = getattr(module, name)
        out[f"{package}.{name}"] = f"{obj.__module__}.{obj.__qualname__}"
    return out


def dataclass_fields(package: str = PACKAGE) -> list[str]:
    """The full names of the fields of the package's public dataclasses.

    Parameters
    ----------
    package : str
        The package's name.

    Returns
    -------
    list of str
        ``module.Class.field`` for every field of every dataclass a public module defines.
    """
    out = []
    for module in public_modules(package):
        for full in public_objects(module):
            obj = getattr(importlib.import_module(module), full.rsplit(".", 1)[-1])
            if inspect.isclass(obj) and dataclasses.is_dataclass(obj):
                out.extend(f"{full}.{f.name}" for f in dataclasses.fields(obj))
    return out


def raises_something(obj) -> bool:
    """Whether a function's own body (nested functions aside) raises an exception.

    Parameters
    ----------
    obj : callable
        A function or method.

    Returns
    -------
    bool
        True if a ``raise`` statement with an exception is in its body.
    """
    try:
        source = textwrap.dedent(inspect.getsource(obj))
        tree = ast.parse(source)
    except (OSError, TypeError, SyntaxError):
        return False
    fn = tree.body[0] if tree.body else None
    if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
        return False

    def walk(node):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
                continue
            if isinstance(child, ast.Raise) and child.exc is not None:
                return True
            if walk(child):
                return True
        return False

    return walk(fn)


def setup(app):
    """Register the benchmark pages, the completeness check and the ``Raises`` check.

    Parameters
    ----------
    app : sphinx.application.Sphinx
        The application.

    Returns
    -------
    dict
        The extension's metadata.
    """
    from sphinx.util import logging

    logger = logging.getLogger(__name__)

    def on_config(app, config):
        benchmark_pages()
        api_pages()
        # a dataclass field is documented in its class's Parameters section; numpydoc would
        # read one whose default is None as an object without a docstring
        config.numpydoc_validation_exclude = set(config.numpydoc_validation_exclude) | {
            rf"^{re.escape(name)}$" for name in dataclass_fields()}

    def excluded(name: str) -> bool:
        return any(re.search(p, name) for p in app.config.numpydoc_validation_exclude)

    warned = set()

    def on_docstring(app, what, name, obj, options, lines):
        if what not in ("function", "method") or excluded(name) or name.rsplit(".", 1)[-1].startswith("_"):
            return
        doc = inspect.getdoc(obj) or ""
        if name not in warned and raises_something(obj) and not RAISES.search(doc):
            warned.add(name)
            logger.warning(f"{name}: raises an exception but its docstring has no Raises section",
                           type="reference", subtype="raises")

    def on_missing(app, env, node, contnode):
        """Resolve ``nonholo.NAME`` (a name of ``nonholo.__all__``) to where it is defined, and
        a short name (``as_geometry``) to the one public object of that name, if only one."""
        if node.get("refdomain") != "py":
            return None
        target = node.get("reftarget", "")
        py = env.get_domain("py")
        full = aliases().get(target)
        if full is None:
            kinds = py.objtypes_for_role(node["reftype"]) or ()
            found = [o for o, entry in py.objects.items()
                     if o.startswith(PACKAGE + ".") and o.endswith("." + target) and entry.objtype in kinds]
            # the nearest in the package's tree to the referring module, if one is nearest
            here = (node.get("py:module") or "").split(".")
            near = {o: len(os.path.commonprefix([o.split("."), here])) for o in found}
            best = [o for o in found if near[o] == max(near.values(), default=0)]
            if len(best) != 1:
                return None
            full = best[0]
        resolved = py.resolve_xref(env, node["refdoc"], app.builder, node["reftype"], full, node, contnode)
        if resolved is None:
            anything = py.resolve_any_xref(env, node["refdoc"], app.builder, full, node, contnode)
            resolved = anything[0][1] if anything else None
        return resolved

    def on_check(app, env):
        py = env.get_domain("py")
        for module in public_modules():
            if module not in py.modules:
                logger.warning(f"public module {module} has no page in the API reference "
                               "(see docs/ext/reference.py)", type="reference", subtype="missing")
                continue
            for full in public_objects(module):
                if full not in py.objects:
                    logger.warning(f"public object {full} has no page in the API reference",
                                   type="reference", subtype="missing")
        for alias, full in aliases().items():
            if full not in py.objects:
                logger.warning(f"{alias} ({full}) has no page in the API reference",
                               type="reference", subtype="missing")

    app.connect("config-inited", on_config, priority=100)   # before numpydoc reads its config
    app.connect("autodoc-process-docstring", on_docstring)
    app.connect("env-check-consistency", on_check)
    app.connect("missing-reference", on_missing)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
