"""Nothing runs that nobody wrote: a mechanism of one's own against an attack round.

The caches of generated modules and compiled kernels are verified before anything in them
runs (:func:`nonholo.codegen.cache.read_entry`): an edited, planted or damaged entry, or
something other than a regular file at its path, is passed over and rebuilt. A user's text
is data: names are identifiers, descriptions and units escaped literals, parameters finite
real numbers, expressions given as text read by a parser that admits only arithmetic
(:func:`derivations.admission.parse`). The derivation has a budget
(:mod:`derivations.budget`) checked before anything is derived. Every cache scenario plants
a payload that would write the marker file ``PWNED``, which must never appear; the caches
are the test's own (``NONHOLO_CACHE_DIR``).
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import re
import subprocess
import sys
import sysconfig
import textwrap
import time
import types
from fractions import Fraction

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from derivations import budget, codegen
from derivations.mechanisms import Mechanism as Symbolic
from derivations.mechanisms import PlatformGeometry
from nonholo import Mechanism, plan
from nonholo.codegen import build, c_extension
from nonholo.codegen import cache as entries
from nonholo.codegen.c_subset import Function

x, y, th, th0, th1, v, w, d, ell = sp.symbols("x y theta theta0 theta1 v w d ell", real=True)
xd, yd, thd = sp.symbols("xdot ydot thetadot", real=True)
TRAILER = dict(coordinates=[x, y, th0, th1], inputs=[v, w],
               rates=[v * sp.cos(th0), v * sp.sin(th0), w, v * sp.sin(th0 - th1)], angles=[th0, th1])
UNICYCLE = dict(coordinates=[x, y, th], inputs=[v, w], rates=[v * sp.cos(th), v * sp.sin(th), w])


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """Caches of the test's own; each warning said anew."""
    monkeypatch.setenv(entries.CACHE_ENV, str(tmp_path / "cache"))
    monkeypatch.setattr(entries, "_WARNED", set())
    return tmp_path / "cache"


@pytest.fixture
def marker(tmp_path):
    """The file a planted payload would write: it must never appear."""
    path = tmp_path / "PWNED"
    yield path
    assert not path.exists(), "a planted payload ran"


def payload(marker) -> str:
    return f"open({str(marker)!r}, 'w').write('pwned')\n"


def entry_of(cache, name):
    """The cached generated module of ``name`` (one)."""
    files = sorted((cache / "generated").glob(f"{name}_*.py"))
    assert len(files) == 1, files
    return files[0]


def fresh_source(name, **arguments):
    return Mechanism.from_equations(name, **arguments, cache=False).module.SOURCE


def no_warning_on_rebuild(name, arguments):
    """A third build reads the repaired entry without a word."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return Mechanism.from_equations(name, **arguments)


# -- the cached generated source is verified before it runs ------------------------------------

def test_an_edited_cached_source_is_not_run_and_the_plan_holds_on_the_user_s_equations(cache, marker):
    """The attack: an edited cache entry runs its code in every later process, and replaces
    the user's equations (``plan`` certified a plan of the edited model). Now the entry's hash
    is checked against the record written with it: the edit is passed over (one warning
    naming the file), the module regenerated, the entry repaired, and the plan holds on the
    equations as written."""
    name = "trailer_edited"
    Mechanism.from_equations(name, **TRAILER)
    path = entry_of(cache, name)
    text = path.read_text()
    assert "    out[2, 1] = 1\n" in text
    path.write_text(payload(marker) + text.replace("    out[2, 1] = 1\n", "    out[2, 1] = 2\n"))
    with pytest.warns(RuntimeWarning, match=re.escape(f"ignored the cache entry {path}") + ".*hash"):
        m = Mechanism.from_equations(name, **TRAILER)
    assert m.module.SOURCE == fresh_source(name, **TRAILER) == path.read_text()
    no_warning_on_rebuild(name, TRAILER)
    goal = np.array([1.0, 0.5, 0.0, 0.0])
    res = plan(np.zeros(4), goal, mechanism=m)
    assert res.success, res.reason
    f = sp.lambdify([TRAILER["coordinates"], TRAILER["inputs"]], TRAILER["rates"], "numpy")
    sol = solve_ivp(lambda t, q: np.array(f(q, res.controls(np.array([t]))[0]), dtype=float),
                    (0.0, res.T), np.zeros(4), method="DOP853", rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(sol.y[:, -1] - goal)) < 1e-8


def test_a_planted_source_without_a_record_or_with_another_s_is_not_run(cache, marker):
    """A file planted at the entry's path — with no record, or with the record of another
    entry copied beside it — is passed over."""
    name = "unicycle_planted"
    Mechanism.from_equations(name, **UNICYCLE)
    path = entry_of(cache, name)
    record = entries.record_path(path)
    good = path.read_text()
    # no record
    record.unlink()
    path.write_text(payload(marker) + good)
    with pytest.warns(RuntimeWarning, match="no record"):
        m = Mechanism.from_equations(name, **UNICYCLE)
    assert m.module.SOURCE == good
    # the record of another definition (its hash and key) beside the planted file
    other = Mechanism.from_equations("unicycle_other", **{**UNICYCLE, "rates": [v * sp.cos(th), v * sp.sin(th), 2 * w]})
    other_path = entry_of(cache, "unicycle_other")
    path.write_text(other_path.read_text().replace("'unicycle_other'", f"'{name}'") + payload(marker))
    record.write_bytes(entries.record_path(other_path).read_bytes())
    entries._WARNED.clear()                                   # the fixture's own set: said anew
    with pytest.warns(RuntimeWarning, match="record of another entry"):
        m = Mechanism.from_equations(name, **UNICYCLE)
    assert m.module.SOURCE == good and other.module.SOURCE != good


@pytest.mark.parametrize("damage", ["truncated", "empty", "binary", "directory", "symlink"])
def test_a_damaged_cache_entry_is_repaired_not_fatal(cache, marker, tmp_path, damage):
    """The attack: a truncated, empty or binary entry failed every later run (SyntaxError,
    AttributeError, UnicodeDecodeError) until deleted by hand. Now it is passed over with a
    warning naming it, regenerated and rewritten; a directory in the way is skipped (the
    module is built without the cache); a symbolic link to elsewhere is never followed and
    its target never written."""
    name = f"unicycle_{damage}"
    Mechanism.from_equations(name, **UNICYCLE)
    path = entry_of(cache, name)
    good = path.read_bytes()
    elsewhere = tmp_path / "elsewhere.py"
    if damage == "truncated":
        path.write_bytes(good[: len(good) // 2] + b"\n" + payload(marker).encode())
    elif damage == "empty":
        path.write_bytes(b"")
    elif damage == "binary":
        path.write_bytes(b"\xff\xfe\x00" + payload(marker).encode() + os.urandom(64))
    elif damage == "directory":
        path.unlink()
        path.mkdir()
        (path / "inside.py").write_text(payload(marker))
    else:                    # a link to a payload, even with a record that matches its bytes
        elsewhere.write_text(payload(marker) + good.decode())
        path.unlink()
        path.symlink_to(elsewhere)
        record = json.loads(entries.record_path(path).read_text())
        record["sha256"] = hashlib.sha256(elsewhere.read_bytes()).hexdigest()
        entries.record_path(path).write_text(json.dumps(record))
    expected = "could not cache" if damage == "directory" else f"ignored the cache entry {path}"
    with pytest.warns(RuntimeWarning) as caught:
        m = Mechanism.from_equations(name, **UNICYCLE)
    messages = " | ".join(str(c.message) for c in caught)
    assert f"ignored the cache entry {path}" in messages and expected in messages, messages
    assert m.module.SOURCE == good.decode()
    if damage == "directory":
        assert path.is_dir()
    else:
        assert not path.is_symlink() and path.read_bytes() == good
        no_warning_on_rebuild(name, UNICYCLE)
    if damage == "symlink":
        assert elsewhere.read_text().startswith("open(")          # the target is untouched


def test_a_fifo_at_a_cache_path_never_blocks(tmp_path, marker):
    """The attack: a FIFO at an entry's path blocked forever. Now it is never opened for
    reading (non-blocking open, checked before use): passed over and replaced, in a fresh
    process bounded in time, both for the generated source and for the compiled module."""
    cache = tmp_path / "cache"
    code = textwrap.dedent(f"""
        import os, warnings, sympy as sp
        warnings.simplefilter("always")
        from nonholo import Mechanism
        from nonholo.integrate import system_kernels
        x, y, th, v, w = sp.symbols("x y theta v w", real=True)
        args = dict(coordinates=[x, y, th], inputs=[v, w], rates=[v*sp.cos(th), v*sp.sin(th), w])
        if os.environ.get("STAGE") == "plant":
            m = Mechanism.from_equations("unicycle_fifo", **args)
            gen = [p for p in os.listdir({str(cache / "generated")!r}) if p.endswith(".py")]
            system_kernels.compile_system(m.module)
            so = [p for p in os.listdir({str(cache)!r}) if p.endswith({sysconfig.get_config_var("EXT_SUFFIX")!r})]
            for p in [os.path.join({str(cache / "generated")!r}, gen[0]), os.path.join({str(cache)!r}, so[0])]:
                os.unlink(p); os.mkfifo(p)
        else:
            with warnings.catch_warnings(record=True) as caught:
                m = Mechanism.from_equations("unicycle_fifo", **args)
                kernels = system_kernels.compile_system(m.module)
            print(kernels.backend, sum("not a regular file" in str(c.message) for c in caught))
    """)
    env = dict(os.environ, NONHOLO_CACHE_DIR=str(cache))
    first = subprocess.run([sys.executable, "-c", code], env={**env, "STAGE": "plant"}, capture_output=True,
                           text=True, timeout=300, check=False)
    assert first.returncode == 0, first.stderr
    if "native kernels unavailable" in first.stderr:
        pytest.skip("no C compiler")
    start = time.perf_counter()
    second = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                            timeout=300, check=False)          # blocked on a FIFO: TimeoutExpired
    assert second.returncode == 0, second.stderr
    assert second.stdout.split() == ["native", "2"]
    assert time.perf_counter() - start < 300
    assert not any(p.is_fifo() for p in cache.rglob("*"))


# -- compiled modules: hashed before they are imported ------------------------------------------

needs_cc = pytest.mark.skipif(build.compiler() is None, reason="no C compiler")


def _toy(x, a):
    s = 0.0
    for i in range(a.shape[0]):
        s += x * a[i]
    return s


def toy_source(name: str, digest: str) -> str:
    return c_extension.extension_source(
        f"nonholo.generated.native.{name}", name,
        [Function(_toy, "toy", {"x": "f8", "a": "f8[1]"})], digest)


def planted_source(name: str, digest: str, marker) -> str:
    """An extension module whose initialisation writes ``marker`` and which claims the
    expected ``SOURCE_DIGEST``: importing it at all is the attack."""
    return textwrap.dedent(f"""
        #include <Python.h>
        #include <stdio.h>
        static struct PyModuleDef def = {{PyModuleDef_HEAD_INIT, "{name}", NULL, -1, NULL}};
        PyMODINIT_FUNC PyInit_{name}(void) {{
            FILE *f = fopen("{marker}", "w");
            if (f) {{ fputs("pwned", f); fclose(f); }}
            PyObject *m = PyModule_Create(&def);
            if (m) PyModule_AddStringConstant(m, "SOURCE_DIGEST", "{digest}");
            return m;
        }}
    """)


@needs_cc
@pytest.mark.parametrize("with_record", [False, True])
def test_a_planted_compiled_module_is_never_imported(cache, marker, tmp_path, with_record):
    """The attack: a compiled module planted at the cache path was imported — its
    initialisation run — before its digest was checked. Now the file's hash is checked
    against the record nonholo wrote when it compiled it, before any import: a planted
    module (without a record, or with the record of the genuine one beside it) is passed
    over, the genuine one compiled and loaded."""
    name = f"toy_planted_{int(with_record)}"
    want = f"{tmp_path.name}-{name}"
    target = cache / f"{name}_{want[:16]}{sysconfig.get_config_var('EXT_SUFFIX') or '.so'}"
    if with_record:
        build.compile_module(name, toy_source(name, want), target, key=want)
        genuine_record = entries.record_path(target).read_bytes()
    build.compile_module(name, planted_source(name, want, marker), target)
    if with_record:
        entries.record_path(target).write_bytes(genuine_record)
    assert target.exists() and not marker.exists()
    with pytest.warns(RuntimeWarning, match=re.escape(f"ignored the cache entry {target}")):
        lib = build.load(name, want, lambda: toy_source(name, want))
    assert lib is not None and lib.SOURCE_DIGEST == want
    assert lib.toy(2.0, np.array([1.0, 2.0, 3.0])) == 12.0


@needs_cc
def test_a_damaged_compiled_module_is_rebuilt(cache, marker, tmp_path, monkeypatch):
    """A truncated module in the cache is not loaded (it would fail to import, or worse):
    recompiled, with a warning naming it."""
    name = "toy_damaged"
    want = f"{tmp_path.name}-{name}"
    monkeypatch.setattr(build, "_LOADED", {})
    lib = build.load(name, want, lambda: toy_source(name, want))
    assert lib is not None
    monkeypatch.setattr(build, "_LOADED", {})               # as a later process
    monkeypatch.delitem(sys.modules, f"nonholo.generated.native.{name}", raising=False)
    target = next(cache.glob(f"{name}_*{sysconfig.get_config_var('EXT_SUFFIX') or '.so'}"))
    good = target.read_bytes()
    target.write_bytes(good[: len(good) // 3])
    with pytest.warns(RuntimeWarning, match=re.escape(f"ignored the cache entry {target}")):
        again = build.load(name, want, lambda: toy_source(name, want))
    assert again is not None and again.toy(1.0, np.ones(2)) == 2.0
    assert target.stat().st_size > len(good) // 3


# -- user text is data ---------------------------------------------------------------------------

def test_a_description_that_closes_the_docstring_is_not_run(cache, marker):
    """The attack: ``description`` was pasted into the generated module's docstring, so one
    closing it ran its next line (and wrote it into the cache); ``'x\"\"\"y'`` gave a
    SyntaxError. Now a description is a line of printable text (a line break: ValueError
    naming ``description``) written only as escaped literals: any quotes round-trip."""
    closing = f'x"""\n{payload(marker)}"""'
    with pytest.raises(ValueError, match="description must be one line of printable text"):
        Mechanism.from_equations("unicycle_described", **UNICYCLE, description=closing)
    assert not (cache / "generated").exists()
    for text in ['x"""y', f'x"""; {payload(marker).strip()}; """', "a \\ backslash, 'quotes' and \"\"\""]:
        m = Mechanism.from_equations("unicycle_described", **UNICYCLE, description=text)
        assert m.description == text and m.module.DESCRIPTION == text
        compile(m.module.SOURCE, "generated", "exec")
    # the symbolic route (from_symbolic) and units alike
    X = sp.Matrix([[sp.cos(th), 0], [sp.sin(th), 0], [0, 1]])
    sym = Symbolic("unicycle_symbolic", f'u"""; {payload(marker).strip()}; """', X=X, coordinates=(x, y, th),
                   inputs=('v"""', "w'"), units=('m"""', "m", "rad"), angles=(False, False, True))
    m = Mechanism.from_symbolic(sym)
    assert m.description == sym.description and m.inputs == ('v"""', "w'") and m.units == ('m"""', "m", "rad")
    with pytest.raises(ValueError, match="units"):
        Mechanism.from_equations("unicycle_units", **UNICYCLE, units={x: 'm"""\n' + payload(marker)})


@pytest.mark.parametrize("name", ["../escaped", "a'b\nc", "two words", "class", "", "x/y", 42])
def test_a_name_must_be_an_identifier(cache, marker, tmp_path, name):
    """The attack: ``from_symbolic`` did not check the name: ``"../"`` wrote the module
    outside the cache, a quote and a line break broke the compiled code. Now every route
    refuses it with ValueError naming ``name``, before writing anything — even a symbolic
    mechanism whose name was changed behind its checks."""
    X = sp.Matrix([[sp.cos(th), 0], [sp.sin(th), 0], [0, 1]])
    with pytest.raises(ValueError, match="name must be a Python identifier"):
        Symbolic(name, "unicycle", X=X, coordinates=(x, y, th), inputs=("v", "w"))
    sym = Symbolic("ok_name", "unicycle", X=X, coordinates=(x, y, th), inputs=("v", "w"))
    object.__setattr__(sym, "name", name)                   # past the dataclass's checks
    with pytest.raises(ValueError, match="name must be a Python identifier"):
        Mechanism.from_symbolic(sym)
    with pytest.raises(ValueError, match="name must be a Python identifier"):
        Mechanism.from_equations(name, **UNICYCLE)
    with pytest.raises(ValueError, match="name must be a Python identifier"):
        entries.cached_source(name, "0" * 64, lambda: payload(marker))
    assert not [p for p in tmp_path.rglob("*") if p.is_file()]


@pytest.mark.parametrize("route", ["from_equations", "from_constraints", "geometry"])
def test_a_string_parameter_is_refused_not_evaluated(cache, marker, route):
    """The attack: a string parameter went to ``sympify``, i.e. to Python's ``eval``:
    ``parameters={d: '__import__("os")'}`` imported a module. Now a parameter is a finite
    real number: text is refused with ValueError naming the parameter."""
    evil = f"__import__('builtins').{payload(marker).strip()}"
    with pytest.raises(ValueError, match=r"parameters: d = .* is text, not a number|geometry: base1\[0\]"):
        if route == "from_equations":
            Mechanism.from_equations("unicycle_param", **{**UNICYCLE, "rates": [v * sp.cos(th), v * sp.sin(th), w / d]},
                                     parameters={d: evil})
        elif route == "from_constraints":
            Mechanism.from_constraints("unicycle_param", coordinates=[x, y, th], velocities=[xd, yd, thd],
                                       inputs=[xd, thd], constraints=[d * xd * sp.sin(th) - yd * sp.cos(th)],
                                       parameters={d: evil})
        else:
            PlatformGeometry(base1=(evil, 1, 0), tip1=(0, 1, 0), base2=(1, 0, 0), tip2=(1, 0, 0),
                             contact=(0, 0, 1), axle=(1, -1, 0))


def test_expressions_given_as_text_are_parsed_not_evaluated(cache, marker):
    """Rates as text are read by a parser that admits only numbers, the declared symbols,
    arithmetic and a fixed set of functions — the same mechanism as from SymPy's
    expressions; anything else is refused naming the rate and the piece."""
    as_text = Mechanism.from_equations("trailer_text", **{**TRAILER, "rates": [
        "v*cos(theta0)", "v * sin(theta0)", "w", "v*sin(theta0 - theta1)"]})
    assert as_text.module.SOURCE == fresh_source("trailer_text", **TRAILER)
    evil = payload(marker).strip()
    for text, piece in [("__import__('os').system('true') or v", "__import__"), (evil, "open"),
                        ("v.__class__", "v.__class__"), ("v[0]", "v[0]"), ("'v'", "'v'"), ("(lambda: v)()", "lambda"),
                        ("[v for v in (1,)][0]", "for"), ("v if w else w", "if"), ("sin(x=v)", "keywords"),
                        ("v ^ 2", "**"), ("2**10**10 * v", "10**10"), ("1j * v", "1j"), ("u * v", "'u'"),
                        ("v * (" * 150 + "v" + ")" * 150, "nested more than 32 deep"),
                        ("(" * 300 + "v" + ")" * 300, "nested too deeply"), ("v" + " + v" * 2000, "characters")]:
        with pytest.raises(ValueError, match=r"rates\[0\]") as refused:
            Mechanism.from_equations("trailer_text_bad", **{**TRAILER, "rates": [text, "v", "w", "v"]}, cache=False)
        assert piece in str(refused.value), (text, str(refused.value))
    with pytest.raises(ValueError, match="rotation must be a 3×3 matrix of nine distinct symbols"):
        Mechanism.from_equations("rotation_text", inputs=[v, w], omega=[v, w, 0], rotation=[[evil] * 3] * 3)


# -- bounded derivation ----------------------------------------------------------------------------

def nested(depth: int) -> sp.Expr:
    e = x
    for _ in range(depth):
        e = sp.sin(e)
    return e


def trig_sum(n: int):
    return (v * sp.Add(*[sp.sin(k * x) * sp.cos(k * y) for k in range(1, n + 1)]),
            "v*(" + " + ".join(f"sin({k}*x)*cos({k}*y)" for k in range(1, n + 1)) + ")")


BEYOND = {
    "300-term trigonometric sum": trig_sum(300),
    "1,000 terms": (v * sp.Add(*[x ** (k % 5) * sp.cos(k * th) for k in range(1, 1001)]),
                    "v*(" + " + ".join(f"x**{k % 5}*cos({k}*theta)" for k in range(1, 1001)) + ")"),
    "nesting depth 300": (v * nested(300), "v*" + "sin(" * 300 + "x" + ")" * 300),
    "300 factors": (v * sp.Mul(*[(1 + x * k) for k in range(1, 301)], evaluate=False),
                    "v*" + "*".join(f"(1 + {k}*x)" for k in range(1, 301))),
    "a power of 400": (v * (x + y + th) ** 400, "v*(x + y + theta)**400"),
}


@pytest.mark.parametrize("label", BEYOND)
def test_the_derivation_has_a_budget(cache, label):
    """The attack: no bound on the derivation — a 300-term trigonometric sum still deriving
    after 100 s with 3 GB resident, 1,000 terms a MemoryError, a nesting 300 deep a
    RecursionError. Now each rate is measured before anything is derived and refused past
    the budget with ValueError naming the rate and the limit, in well under 5 s (as text
    too, and on the symbolic route)."""
    rate, text = BEYOND[label]
    for route in ("equations", "text", "symbolic"):
        start = time.perf_counter()
        with pytest.raises(ValueError, match=r"(rates\[0\]|X\[0, 0\]).*(budget|more than)"):
            if route == "equations":
                Mechanism.from_equations("budget_test", coordinates=[x, y, th], inputs=[v, w], rates=[rate, w, v])
            elif route == "text":
                Mechanism.from_equations("budget_test", coordinates=[x, y, th], inputs=[v, w], rates=[text, "w", "v"])
            else:
                Mechanism.from_symbolic(Symbolic("budget_test", "big", X=sp.Matrix([[rate / v, 0], [0, 1], [1, 0]]),
                                                 coordinates=(x, y, th), inputs=("v", "w")))
        assert time.perf_counter() - start < 5, (label, route)
    assert not (cache / "generated").exists()


def test_within_the_budget_the_costly_steps_stay_bounded(cache):
    """A rate just within the budget that SymPy's simplify and expand would take minutes on
    (a large sum, a large denominator) is derived and generated in seconds: those steps are
    applied only to small expressions (derivations.budget)."""
    big_sum = v * sp.Add(*[sp.sin(k * x) * sp.cos(k * y) for k in range(1, 100)])
    denominator = v / sp.Add(*[sp.cos(k * x) for k in range(1, 60)])
    assert budget.measure(big_sum, "sum") <= budget.NODES and budget.measure(denominator, "den") <= budget.NODES
    start = time.perf_counter()
    m = Mechanism.from_equations("budget_within", coordinates=[x, y, th], inputs=[v, w],
                                 rates=[big_sum, denominator, w], cache=False)
    assert time.perf_counter() - start < 120
    q = np.array([0.3, -0.2, 0.1])
    G = sp.lambdify([[x, y, th]], sp.Matrix([[big_sum / v, 0], [denominator / v, 0], [0, 1]]), "numpy")
    np.testing.assert_allclose(m.G(np.eye(3), q), np.array(G(q), dtype=float), rtol=1e-12)


# -- constants checked up front ---------------------------------------------------------------------

BAD_IN_RATES = [sp.I, 1 + sp.I, float("inf"), -float("inf"), float("nan"), 1e400, sp.Float("1e400"), 10 ** 400,
                sp.Integer(10) ** 400, sp.oo, sp.zoo, sp.nan, sp.exp(1000), sp.asin(2), sp.sqrt(-2), 1j]
BAD_CONSTANTS = BAD_IN_RATES + [complex(1, 0), np.complex128(2), np.float64("nan"), "1.0", b"1", None, [1.0], True,
                                sp.Symbol("h"), sp.Eq(x, 1)]


@pytest.mark.parametrize("value", BAD_CONSTANTS, ids=lambda c: repr(c)[:20])
def test_bad_constants_are_refused_up_front(cache, value):
    """The attack: complex, infinite, huge or NaN constants were accepted, then failed deep
    inside ``plan`` (TypeError, OverflowError, LinAlgError). Now they are refused with
    ValueError naming the parameter — or the rate, given in it."""
    rates = [v * sp.cos(th), v * sp.sin(th), w / d]
    with pytest.raises(ValueError, match="parameters: d"):
        Mechanism.from_equations("unicycle_constant", **{**UNICYCLE, "rates": rates}, parameters={d: value})
    if any(value is bad for bad in BAD_IN_RATES):
        with pytest.raises(ValueError, match=r"rates\[2\]"):
            Mechanism.from_equations("unicycle_constant", **{**UNICYCLE, "rates": [*rates[:2], w * value]})


def test_a_product_of_constants_beyond_float_range_is_refused_naming_the_rate(cache):
    """Each parameter is a float, their product in a rate is not: refused naming the rate."""
    with pytest.raises(ValueError, match=r"rates\[2\] \(with the parameters' values\).*beyond float range"):
        Mechanism.from_equations("unicycle_product", **{**UNICYCLE, "rates": [v * sp.cos(th), v * sp.sin(th), d * ell * w]},
                                 parameters={d: 1e300, ell: 1e300})


@pytest.mark.parametrize("value", [2, 2.5, np.float64(0.5), np.int32(3), Fraction(1, 3), sp.pi, sp.sqrt(2),
                                   sp.Rational(3, 7), 10 ** 300, sp.Float("1e-300")], ids=repr)
def test_good_constants_are_accepted(value):
    m = Mechanism.from_equations("unicycle_good", **{**UNICYCLE, "rates": [v * sp.cos(th), v * sp.sin(th), w / d]},
                                 parameters={d: value}, cache=False)
    assert m.G(np.eye(3), np.zeros(3))[2, 1] == pytest.approx(1 / float(value), rel=1e-12)


def test_a_frozen_symbolic_mechanism_changed_behind_its_checks_is_checked_again(cache, marker):
    """``from_symbolic`` checks what it is given, not only what the dataclass checked on
    construction: text changed afterwards, or an entry past the budget, is refused."""
    X = sp.Matrix([[sp.cos(th), 0], [sp.sin(th), 0], [0, 1]])
    sym = Symbolic("unicycle_changed", "unicycle", X=X, coordinates=(x, y, th), inputs=("v", "w"))
    bad = dataclasses.replace(sym)
    object.__setattr__(bad, "description", f'x"""\n{payload(marker)}"""')
    with pytest.raises(ValueError, match="description"):
        Mechanism.from_symbolic(bad)
    object.__setattr__(bad, "description", "unicycle")
    object.__setattr__(bad, "X", sp.Matrix([[nested(300), 0], [0, 1], [1, 0]]))
    with pytest.raises(ValueError, match=r"X\[0, 0\].*nested more than"):
        Mechanism.from_symbolic(bad)
    object.__setattr__(bad, "X", X)
    object.__setattr__(bad, "inputs", (sp.Symbol(f"__import__('builtins').{payload(marker).strip()}"), "w"))
    with pytest.raises(ValueError, match=r"inputs\[0\] must be a string"):
        Mechanism.from_symbolic(bad)
    object.__setattr__(bad, "inputs", ("v", "w"))
    # the derivation's data, which the code generator prints from, is checked too
    code = sp.Symbol(f"__import__('builtins').{payload(marker).strip()}")
    object.__setattr__(bad, "derivation", {"auxiliaries": ((code, x),)})
    with pytest.raises(ValueError, match=r"auxiliaries\[0\] must define a symbol named by an identifier"):
        Mechanism.from_symbolic(bad)
    geometry = dict(base1=(payload(marker), 0, 0), tip1=(0, 1, 0), base2=(1, 0, 0), tip2=(1, 0, 0),
                    contact=(0, 0, 1), axle=(1, 0, 0))
    object.__setattr__(bad, "derivation", {"geometry": types.SimpleNamespace(**geometry)})
    with pytest.raises(ValueError, match=r"geometry base1\[0\] = .* is text"):
        Mechanism.from_symbolic(bad)
    with pytest.raises(ValueError, match="cannot be printed into code"):
        codegen.check_printed([x + code])
