"""The package's import structure, from its source (``ast``, nothing is imported):

- the subpackages form ordered layers (:data:`LAYERS`): no import from a lower layer to a
  higher one, hence no cycle between layers; the import graph has no cycle at all;
- no module imports a private name (``_x``) from another ``nonholo`` module;
- ``derivations`` (SymPy) imports nothing from ``nonholo``; no two modules share a name.

Every ``import``/``from … import`` statement counts, wherever it is (module level, inside a
function, under ``if TYPE_CHECKING``), relative or absolute. ``from P import x`` is an
edge to the module ``P.x`` when ``x`` is a submodule of the package ``P``, else to ``P``.
The implicit import of a module's parent packages is not an edge (every module would
otherwise depend on ``nonholo/__init__``).
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = "nonholo"


def module_files() -> dict[str, Path]:
    """``{"nonholo.x.y": path}`` for every module of the package (``__init__`` as the package)."""
    out = {}
    for path in sorted((ROOT / PACKAGE).rglob("*.py")):
        parts = list(path.relative_to(ROOT).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


MODULES = module_files()


def is_package(name: str) -> bool:
    return MODULES[name].name == "__init__.py"


def resolve(module: str, level: int, target: str | None) -> str:
    """The absolute name of ``from <level dots><target> import …`` written in ``module``."""
    if level == 0:
        return target or ""
    base = module.split(".") if is_package(module) else module.split(".")[:-1]
    base = base[:len(base) - (level - 1)] if level > 1 else base
    return ".".join(base + ([target] if target else []))


def imports(module: str) -> list[tuple[str, str | None, int]]:
    """``(imported module, imported name or None, line)`` for every import in ``module``,
    restricted to ``nonholo`` modules."""
    tree = ast.parse(MODULES[module].read_text(), filename=str(MODULES[module]))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name == PACKAGE or alias.name.startswith(PACKAGE + "."):
                    out.append((alias.name, None, node.lineno))
        elif isinstance(node, ast.ImportFrom):
            src = resolve(module, node.level, node.module)
            if not (src == PACKAGE or src.startswith(PACKAGE + ".")):
                continue
            for alias in node.names:
                sub = f"{src}.{alias.name}"
                if sub in MODULES:
                    out.append((sub, None, node.lineno))           # from package import submodule
                else:
                    out.append((src, alias.name, node.lineno))
    return out


def graph() -> dict[str, set[str]]:
    edges = {m: set() for m in MODULES}
    for m in MODULES:
        for target, _, _ in imports(m):
            assert target in MODULES, f"{m} imports {target}, which is not a module of the package"
            if target != m:
                edges[m].add(target)
    return edges


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(edges[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


# -- the checker itself, on small examples ------------------------------------------------------

def test_resolution_of_relative_imports():
    assert resolve("nonholo.planning.core", 2, None) == "nonholo"
    assert resolve("nonholo.planning.core", 2, "numerics") == "nonholo.numerics"
    assert resolve("nonholo.planning.core", 1, "strategy_paper") == "nonholo.planning.strategy_paper"
    assert resolve("nonholo.planning", 1, "core") == "nonholo.planning.core"       # a package's own
    assert resolve("nonholo.model.catalog", 2, "generated") == "nonholo.generated"
    assert resolve("nonholo", 1, "model") == "nonholo.model"


def test_cycle_finder():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": set()}) == []
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


@pytest.mark.slow
def test_the_graph_sees_every_form_of_import():
    """Known imports of the package, one of each form."""
    edges = graph()
    assert "nonholo.numerics.kernels" in edges["nonholo.planning.strategy_paper"]   # from ..numerics import kernels
    assert "nonholo.motion.frame_controls" in edges["nonholo.planning.result_builder"]   # from ..x.y import X
    assert "nonholo.generated" in edges["nonholo.model.catalog"]           # from ..generated import X
    assert "nonholo.planning.core" in edges["nonholo.planning.strategy_paper"]   # from .core import X
    # imports inside functions count too
    inner = [(m, t) for m in MODULES for node in ast.walk(ast.parse(MODULES[m].read_text()))
             if isinstance(node, ast.FunctionDef)
             for sub in ast.walk(node) if isinstance(sub, ast.ImportFrom) and sub.level
             for t in [resolve(m, sub.level, sub.module)]]
    for m, t in inner:
        assert t in edges[m] or any(x.startswith(t + ".") for x in edges[m]), (m, t)


def test_layer_of_every_module():
    assert layer("nonholo.numerics.jit") == "numerics"
    assert layer("nonholo.planning.core") == "planning"
    assert layer("nonholo") == "nonholo"
    assert layer("nonholo.constraints") == "nonholo"          # a top module: the public face
    assert layer("nonholo.model") == "model"
    assert layer("nonholo.codegen.emit") == "codegen"
    assert LAYERS.index("numerics") < LAYERS.index("planning") < LAYERS.index("cli")
    # code generation sits just above what it generates; a mechanism is data the integrator compiles
    assert LAYERS.index("generated") < LAYERS.index("codegen") < LAYERS.index("numerics")
    assert LAYERS.index("codegen") < LAYERS.index("model") < LAYERS.index("integrate")


# -- the package ----------------------------------------------------------------------------

#: The subpackages from the bottom up: a module may import from its own layer and the layers
#: below it, never from a layer above (``nonholo`` itself, the public face, is the top).
LAYERS = ("generated", "codegen", "numerics", "spaces", "controls", "model", "integrate", "motion",
          "certify", "io", "planning", "physics", "viz", "batch", "dynobench", "paper", "cli", "nonholo")

#: At most this many modules directly in ``nonholo/`` besides the subpackages.
MAX_TOP_MODULES = 12


def layer(module: str) -> str:
    """The subpackage of ``module``; ``nonholo`` for the package and its top modules."""
    parts = module.split(".")
    return parts[1] if len(parts) > 2 or (len(parts) == 2 and is_package(module)) else "nonholo"


def test_every_module_is_parsed():
    assert {"nonholo", "nonholo.model.catalog", "nonholo.model.mechanism", "nonholo.integrate.cf4",
            "nonholo.integrate.compiled", "nonholo.codegen", "nonholo.codegen.emit", "nonholo.codegen.build",
            "nonholo.planning.core", "nonholo.planning.strategy_robust",
            "nonholo.generated.platform"} <= set(MODULES)


def test_every_module_is_in_a_layer():
    unknown = sorted(m for m in MODULES if layer(m) not in LAYERS)
    assert not unknown, f"modules outside the layers {LAYERS}: {unknown}"


def test_no_import_from_a_lower_layer_to_a_higher_one():
    upward = [f"{m} ({layer(m)}) imports {t} ({layer(t)})"
              for m, targets in graph().items() for t in sorted(targets)
              if LAYERS.index(layer(t)) > LAYERS.index(layer(m))]
    assert not upward, "imports from a lower layer to a higher one:\n" + "\n".join(upward)


def reached(module: str, edges: dict[str, set[str]]) -> set[str]:
    """The modules ``module`` imports, directly or through others."""
    seen, todo = set(), [module]
    while todo:
        for t in edges[todo.pop()] - seen:
            seen.add(t)
            todo.append(t)
    return seen


def test_a_mechanism_is_data_the_integrator_compiles():
    """The mechanism imports neither the integrator (at all) nor the compiler of native
    modules (itself); the integrator compiles a mechanism's kernels; code generation lives
    in one subpackage and imports nothing above it."""
    edges = graph()
    from_mechanism = reached("nonholo.model.mechanism", edges)
    assert not {m for m in from_mechanism if layer(m) == "integrate"}, sorted(from_mechanism)
    assert not {m for m in edges["nonholo.model.mechanism"] if m in ("nonholo.codegen.build", "nonholo.codegen.emit")}
    assert "nonholo.model.mechanism" not in reached("nonholo.integrate.system_kernels", edges)
    assert "nonholo.codegen.build" in edges["nonholo.integrate.system_kernels"]
    codegen = [m for m in MODULES if layer(m) == "codegen"]
    assert {layer(t) for m in codegen for t in edges[m]} <= {"generated", "codegen"}


def test_few_modules_directly_in_the_package():
    top = [p.name for p in (ROOT / PACKAGE).glob("*.py") if p.name != "__init__.py"]
    assert len(top) <= MAX_TOP_MODULES, top


def test_no_two_modules_share_a_name():
    """No two modules of ``nonholo`` and ``derivations`` have the same file name (``__init__``,
    ``__main__`` — the names Python gives a package and its ``python -m`` entry — and the
    generated modules, named after their mechanisms, aside)."""
    files = [p for tree in (PACKAGE, "derivations") for p in (ROOT / tree).rglob("*.py")
             if p.name not in ("__init__.py", "__main__.py") and "generated" not in p.parts]
    seen = {}
    for p in files:
        seen.setdefault(p.stem, []).append(str(p.relative_to(ROOT)))
    twice = {k: v for k, v in seen.items() if len(v) > 1}
    assert not twice, twice


def test_derivations_import_nothing_from_the_package():
    found = []
    for path in sorted((ROOT / "derivations").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level else [])
            found += [f"{path.name}:{node.lineno}: {n}" for n in names
                      if n == PACKAGE or n.startswith(PACKAGE + ".")]
    assert not found, "derivations import nonholo:\n" + "\n".join(found)


def test_no_import_cycle():
    found = cycles(graph())
    assert not found, "import cycles among nonholo modules: " + "; ".join(" <-> ".join(c) for c in found)


@pytest.mark.slow
def test_no_private_name_is_imported_from_another_module():
    offending = [f"{m}:{line}: from {src} import {name}"
                 for m in MODULES for src, name, line in imports(m)
                 if name is not None and name.startswith("_") and not name.startswith("__") and src != m]
    offending += [f"{m}:{line}: import {src}" for m in MODULES for src, name, line in imports(m)
                  if name is None and any(p.startswith("_") and not p.startswith("__")
                                          for p in src.split("."))]
    assert not offending, "private names imported across nonholo modules:\n" + "\n".join(offending)


@pytest.mark.parametrize("module", sorted(MODULES))
def test_imports_resolve_to_modules_of_the_package(module):
    for target, _, line in imports(module):
        assert target in MODULES, f"{module}:{line} imports {target}"


def test_the_tests_mirror_the_package():
    """Each folder of ``tests/`` is a subpackage's (its tests), or holds the tests of the
    whole project, the derivations or the peer baselines; no test file lies loose."""
    folders = {p.name for p in (ROOT / "tests").iterdir() if p.is_dir() and p.name not in ("data", "__pycache__")}
    subpackages = {p.name for p in (ROOT / "nonholo").iterdir() if (p / "__init__.py").exists()}
    assert folders - subpackages <= {"project", "derivations", "peers"}, folders - subpackages
    assert not list((ROOT / "tests").glob("test_*.py"))
    untested = subpackages - folders - {"generated"}
    assert not untested, f"subpackages without tests of their own: {sorted(untested)}"
