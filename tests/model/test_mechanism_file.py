"""A mechanism of one's own in a data file (nonholo/model/mechanism_file.py and the
definition's modules beside it, ``Mechanism.from_file``/``to_file``, ``catalog.resolve``):
read as data and never run, refused naming the file, the line and the field; accepted by
``nonholo plan``, sweep tables, the atlas and plan files, which carry its definition."""
import builtins
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import nonholo
from nonholo.batch import atlas, result_store, sweep
from nonholo.cli.entry import main
from nonholo.io import problems
from nonholo.io.result import PlanResult
from nonholo.model import catalog, definition_forms, field_places, mechanism_file
from nonholo.model.mechanism import Mechanism
from nonholo.spaces import so3

ROOT = Path(__file__).resolve().parents[2]
#: The example the guide shows (docs/guide/mechanisms.md, "A mechanism in one file").
EXAMPLE = ROOT / "docs" / "guide" / "car_trailer.toml"
#: A goal the car with its trailer reaches on a local plan (a step forward).
START, GOAL = [0.0, 0.0, 0.0, 0.0, 0.0], [0.3, 0.0, 0.0, 0.0, 0.0]


def trailer_field(q, L=1.0, d=1.5) -> np.ndarray:
    """The car with a trailer's ``G(q)``, written out here (independently of the file)."""
    x, y, th, phi, th1 = q
    return np.array([[math.cos(th), 0.0], [math.sin(th), 0.0], [math.tan(phi) / L, 0.0], [0.0, 1.0],
                     [math.sin(th - th1) / d, 0.0]])


def random_states(n, k=5, seed=7):
    rng = np.random.default_rng(seed)
    q = rng.uniform(-2.0, 2.0, size=(n, k))
    if k > 3:
        q[:, 3] = rng.uniform(-1.2, 1.2, size=n)          # steering away from φ = ±π/2
    return q


@pytest.fixture(scope="module")
def trailer():
    return Mechanism.from_file(EXAMPLE)


# -- reading and writing ---------------------------------------------------------------------

def test_the_example_file_is_the_car_with_a_trailer(trailer):
    assert trailer.name == "car_trailer" and trailer.state_space == "R^5"
    assert trailer.coordinates == ("x", "y", "theta", "phi", "theta1") and trailer.inputs == ("v", "w")
    assert trailer.angles == (False, False, True, True, True)
    assert trailer.units == ("m", "m", "rad", "rad", "rad")
    for q in random_states(20):
        np.testing.assert_allclose(trailer.G(np.eye(3), q), trailer_field(q), rtol=1e-13, atol=1e-14)
    # Δ: the rates blow up where cos φ = 0, and only there
    assert abs(trailer.delta(np.eye(3), np.array([0.0, 0.0, 0.0, math.pi / 2, 0.0]))) < 1e-12
    assert abs(trailer.delta(np.eye(3), np.zeros(5))) > 0.5
    assert trailer.bounds == {"inputs": {"v": (-1.0, 1.0), "w": (-math.inf, math.inf)},
                              "coordinates": {"phi": (-0.6, 0.6)}}
    assert type(trailer.drawing).__name__ == "Drawing" and len(trailer.drawing.bodies) == 2
    assert trailer.definition["parameters"] == {"L": 1.0, "d": 1.5}
    assert trailer.definition["rates"]["theta1"] == "v*sin(theta - theta1)/d"


def test_a_file_round_trips_to_the_same_definition_and_numbers(trailer, tmp_path):
    path = trailer.to_file(tmp_path / "copy.toml")
    back = Mechanism.from_file(path)
    assert back.definition == trailer.definition
    assert back.bounds == trailer.bounds and back.drawing.to_mapping() == trailer.drawing.to_mapping()
    for q in random_states(30, seed=3):
        np.testing.assert_array_equal(back.G(np.eye(3), q), trailer.G(np.eye(3), q))
    # and again: the written file is a fixed point
    assert Mechanism.from_file(back.to_file(tmp_path / "again.toml")).definition == trailer.definition
    assert (tmp_path / "again.toml").read_text() == path.read_text()


def test_from_equations_records_its_sympy_equations_as_text_that_reads_back(tmp_path):
    x, y, th = sp.symbols("x y theta")
    v, w, k = sp.symbols("v w k")
    third = 1 / 3                                        # a float with all its digits
    rates = [v * sp.cos(th) + sp.Rational(1, 3) * w * sp.atan2(y, 1 + x**2),
             v * sp.sin(th) * sp.sqrt(1 + x**2) + third * w * sp.tanh(y) * sp.cbrt(2 + x**2),
             k * w * sp.exp(-x**2) / sp.cosh(y)]
    m = Mechanism.from_equations("recorded", coordinates=[x, y, th], inputs=[v, w], rates=rates,
                                 angles=[th], parameters={k: 2.5}, units={x: "m", y: "m"},
                                 description="text of SymPy expressions")
    d = m.definition
    assert d["rates"]["x"] == str(rates[0]) and "0.3333333333333333" in d["rates"]["y"]
    assert d["parameters"] == {"k": 2.5} and d["units"] == {"x": "m", "y": "m"}
    # the text, parsed back by the admission parser, is the same expression
    from derivations import admission

    table = {s.name: s for s in (x, y, th, v, w, k)}
    for c, e in zip("x y theta".split(), rates):
        assert sp.simplify(admission.parse(d["rates"][c], table, c) - e) == 0
    back = Mechanism.from_file(m.to_file(tmp_path / "recorded.toml"))
    assert back.definition == d
    G = sp.lambdify((x, y, th), sp.Matrix(rates).subs(k, 2.5).jacobian([v, w]), "numpy")
    for q in random_states(20, k=3, seed=11):
        np.testing.assert_allclose(back.G(np.eye(3), q), np.array(G(*q), dtype=float), rtol=1e-13,
                                   atol=1e-14)
        np.testing.assert_array_equal(back.G(np.eye(3), q), m.G(np.eye(3), q))


def test_an_orientation_file_round_trips(tmp_path):
    path = tmp_path / "body.toml"
    path.write_text('name = "rate_body"\ninputs = ["u1", "u2"]\n'
                    'omega = ["u1*r11 + u2*r12", "u1*r21 + u2*r22", "u1*r31 + u2*r32"]\n')
    m = Mechanism.from_file(path)
    assert m.state_space == "SO(3)"
    R = so3.from_rpy(0.3, -0.4, 1.1)
    np.testing.assert_allclose(m.L(R), R[:, :2], atol=1e-15)        # ω = R (u1 e1 + u2 e2)
    assert Mechanism.from_file(m.to_file(tmp_path / "back.toml")).definition == m.definition


def test_a_catalog_mechanism_has_no_definition_and_is_not_written(tmp_path):
    car = catalog.get("car")
    assert car.definition is None
    with pytest.raises(ValueError, match="mechanism 'car' has no definition as data"):
        car.to_file(tmp_path / "car.toml")
    assert not (tmp_path / "car.toml").exists()


def test_resolve_takes_a_mechanism_a_name_a_file_and_a_definition(trailer, tmp_path):
    assert catalog.resolve(trailer) is trailer
    assert catalog.resolve("car") is catalog.get("car")
    (tmp_path / "sub").mkdir()
    copy = trailer.to_file(tmp_path / "sub" / "t.toml")
    by_file = catalog.resolve("sub/t.toml", base=tmp_path)
    assert by_file.definition == trailer.definition
    assert catalog.resolve(str(copy)) is by_file                       # built once per process
    assert catalog.resolve(definition_forms.json_data(trailer.definition)) is by_file
    with pytest.raises(ValueError, match="unknown mechanism 'teapot'"):
        catalog.resolve("teapot")
    with pytest.raises(ValueError, match=re.escape(f"{tmp_path / 'nothere.toml'}: no such mechanism file")):
        catalog.resolve("nothere.toml", base=tmp_path)


# -- bad files ---------------------------------------------------------------------------------

BASE = """\
name = "cart"
coordinates = ["x", "y", "theta"]
inputs = ["v", "w"]
angles = ["theta"]

[parameters]
k = 2.0

[rates]
x = "v*cos(theta)"
y = "v*sin(theta)"
theta = "k*w"
"""

MARKER = "nonholo-mechanism-file-marker"
ENV = "NONHOLO_MECHANISM_FILE_PWNED"


def line(n, text, base=BASE):
    """``base`` with its line ``n`` (from 1) replaced by ``text`` (``None``: removed)."""
    lines = base.splitlines()
    lines[n - 1:n] = [] if text is None else [text]
    return "\n".join(lines) + "\n"


def run(code):
    return f"__import__('os').system('touch {MARKER}')" if code == "touch" else code


BAD = {
    # id: (text, line, field, what the message says)
    "TOML syntax error": (line(12, 'theta = "k*w'), 12, "rates.theta", "invalid TOML"),
    "unknown function": (line(12, 'theta = "evil(w)"'), 12, "rates.theta", "not a call of an allowed function"),
    "attribute access": (line(10, 'x = "x.__class__"'), 10, "rates.x", "not allowed"),
    "__import__": (line(10, f'x = "{run("touch")}"'), 10, "rates.x", "not a call of an allowed function"),
    "open()": (line(11, f"y = \"open('{MARKER}', 'w')\""), 11, "rates.y", "not a call of an allowed function"),
    "os.environ": (line(11, f"y = \"__import__('os').environ.__setitem__('{ENV}', '1')\""), 11, "rates.y",
                   "not a call of an allowed function"),
    "subscript": (line(12, 'theta = "w[0]"'), 12, "rates.theta", "not allowed"),
    "lambda": (line(12, 'theta = "(lambda: w)()"'), 12, "rates.theta", "not a call of an allowed function"),
    "comprehension": (line(12, f'theta = "[{run("touch")} for _ in (1,)][0]"'), 12, "rates.theta", "not allowed"),
    "generator": (line(12, 'theta = "sum(w for _ in (1, 2))"'), 12, "rates.theta", "not a call"),
    "f-string": (line(12, "theta = \"f'{w}'\""), 12, "rates.theta", "not allowed"),
    "string constant": (line(12, "theta = \"'w'\""), 12, "rates.theta", "not a number"),
    "rate of an undeclared coordinate": (BASE + 'z = "v"\n', 13, "rates.z", "not one of the coordinates"),
    "missing rate": (line(12, None), 9, "rates.theta", "is missing"),
    "input not used": (line(3, 'inputs = ["v", "w", "brake"]'), 3, "inputs", "'brake' is used by no rate"),
    "parameter a list": (line(7, "k = [1, 2]"), 7, "parameters.k", "must be a number"),
    "parameter as text": (line(7, f'k = "{run("touch")}"'), 7, "parameters.k", "text is never evaluated"),
    "parameter a boolean": (line(7, "k = true"), 7, "parameters.k", "must be a number"),
    "parameter infinite": (line(7, "k = inf"), 7, "parameters.k", "infinite"),
    "parameter a date": (line(7, "k = 1979-05-27"), 7, "parameters.k", "must be a number"),
    "huge exponent": (line(12, 'theta = "w*theta**1000"'), 12, "rates.theta", "exponent beyond the budget"),
    "huge constant": (line(12, 'theta = "w*10**400"'), 12, "rates.theta", "beyond"),
    "undeclared symbol": (line(12, 'theta = "w*q7"'), 12, "rates.theta", "is not declared"),
    "coordinates not a list": (line(2, 'coordinates = "x"'), 2, "coordinates", "must be a list of names"),
    "a coordinate twice": (line(2, 'coordinates = ["x", "x", "theta"]'), 2, "coordinates", "names 'x' twice"),
    "a name that is not an identifier": (line(1, 'name = "my cart"'), 1, "name", "Python identifier"),
    "a coordinate that is a keyword": (line(2, 'coordinates = ["x", "y", "lambda"]'), 2, "coordinates",
                                       "not a name"),
    "a parameter named like a function": (line(6, "[parameters]\nsin = 1.0", BASE), 7, "parameters.sin",
                                          "name of a function"),
    "an input that is a coordinate": (line(3, 'inputs = ["x", "w"]'), 3, "inputs", "also one of the coordinates"),
    "unknown top-level key": (line(5, 'script = "import os"'), 5, "script", "not a key of a mechanism file"),
    "empty file": ("", 1, "name", "is missing"),
    "bounds low > high": (BASE + "[bounds.coordinates]\ntheta = [1.0, -1.0]\n", 14, "bounds.coordinates.theta",
                          "low > high"),
    "bounds of an undeclared input": (BASE + "[bounds.inputs]\nbrake = [0, 1]\n", 14, "bounds.inputs.brake",
                                      "not one of the inputs"),
    "bounds as text": (BASE + "[bounds.inputs]\nv = [\"-1\", 1]\n", 14, "bounds.inputs.v", "must hold numbers"),
    "angles not coordinates": (line(4, 'angles = ["phi"]'), 4, "angles", "not one of the coordinates"),
    "description not one line": (line(5, 'description = "a\\nb"'), 5, "description", "one line"),
    "rate not affine in the inputs": (line(12, 'theta = "w**2 + v"'), 12, "rates.theta", "its term w**2 is not affine"),
    "rate a table": (line(10, "x = {a = 1}"), 10, "rates.x", "must be an expression"),
    "nested too deeply": (line(10, 'x = "' + "(" * 300 + "v" + ")" * 300 + '"'), 10, "rates.x", "nested"),
    "drawing runs nothing": (BASE + f'[[drawing.bodies]]\nx = "{run("touch")}"\ny = "y"\nlength = 1\nwidth = 1\n',
                             14, "drawing.bodies[0].x", "drawing.bodies[0].x"),
    "drawing of an unknown name": (BASE + '[[drawing.bodies]]\nx = "x"\ny = "y"\nlength = 1\nwidth = 1\n'
                                   '[[drawing.bodies]]\nx = "x"\ny = "foo"\nlength = 1\nwidth = 1\n',
                                   20, "drawing.bodies[1].y", "foo"),
}


@pytest.fixture
def no_evaluation(monkeypatch, tmp_path):
    """Fail at once if anything hands text to Python's ``eval`` or SymPy's ``sympify``; run
    in a directory of its own (where the payloads would leave their marker)."""
    Mechanism.from_file(EXAMPLE)             # warm: the modules a derivation imports are loaded
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv(ENV, raising=False)

    def no_eval(*args, **kwargs):
        raise AssertionError(f"eval called with {args[:1]!r}")

    real = sp.sympify

    def no_text(value, *args, **kwargs):
        if isinstance(value, str):
            raise AssertionError(f"sympify called on text {value!r}")
        return real(value, *args, **kwargs)

    monkeypatch.setattr(builtins, "eval", no_eval)
    for module in ("sympy", "sympy.core.sympify"):
        monkeypatch.setattr(sys.modules[module], "sympify", no_text)
    yield tmp_path
    assert not (tmp_path / MARKER).exists() and ENV not in os.environ


@pytest.mark.parametrize("case", sorted(BAD))
def test_a_bad_file_is_refused_naming_the_file_the_line_and_the_field(case, no_evaluation):
    text, n, field, says = BAD[case]
    path = no_evaluation / f"bad_{re.sub(r'[^a-z]+', '_', case.lower())}.toml"
    path.write_text(text)
    with pytest.raises(ValueError) as info:
        Mechanism.from_file(path)
    message = str(info.value)
    assert re.match(rf"{re.escape(str(path))}, line {n}(, column \d+)?, {re.escape(field)}: ", message), message
    assert says in message, message
    # the same through the resolver, as the commands call it
    with pytest.raises(ValueError, match=re.escape(f"{path}, line {n}")):
        catalog.resolve(str(path))


def test_at_least_twenty_kinds_of_bad_file_are_tried():
    assert len(BAD) >= 20


def test_a_path_that_is_not_a_file_or_too_large_is_refused_naming_it(tmp_path, no_evaluation):
    (tmp_path / "dir.toml").mkdir()
    fifo = tmp_path / "fifo.toml"
    os.mkfifo(fifo)                              # read, it would block: refused before that
    big = tmp_path / "big.toml"
    big.write_text(BASE + "#" * (mechanism_file.MAX_BYTES + 1) + "\n")
    cases = {tmp_path / "dir.toml": "is a directory", fifo: "not a regular file",
             tmp_path / "none.toml": "no such mechanism file", big: "more than 1,000,000"}
    for path, says in cases.items():
        with pytest.raises(ValueError, match=f"^{re.escape(str(path))}: .*{says}"):
            Mechanism.from_file(path)


def test_a_file_that_is_not_utf8_is_refused_naming_the_line(tmp_path):
    path = tmp_path / "latin.toml"
    path.write_bytes(BASE.encode() + b'description = "caf\xe9"\n')
    with pytest.raises(ValueError, match=rf"^{re.escape(str(path))}, line 13: not UTF-8"):
        Mechanism.from_file(path)


def test_fields_are_found_on_their_lines():
    text = ('name = "a"\n[rates]\n  x = "v"\n"y" = "w"\n[bounds.inputs]\nv = [0, 1]\n'
            '[[drawing.bodies]]\nx = "x"\n[[drawing.bodies]]\nx = "y"\n')
    assert field_places.line_of(text, "name") == 1
    assert field_places.line_of(text, "rates.x") == 3 and field_places.line_of(text, "rates.y") == 4
    assert field_places.line_of(text, "rates.z") == 2                  # missing: its table
    assert field_places.line_of(text, "bounds.inputs.v") == 6
    assert field_places.line_of(text, "drawing.bodies[1].x") == 10
    assert field_places.line_of(text, "units.x") == 1                  # nowhere: the file's start
    assert field_places.field_at(text, 4) == "rates.y" and field_places.field_at(text, 5) == "bounds.inputs"


# -- planning, plan files ------------------------------------------------------------------------

def test_a_state_of_the_wrong_size_is_refused_naming_the_argument(trailer, capsys):
    with pytest.raises(ValueError, match=r"^start must be a vector of its 5 coordinates .* for mechanism "
                                         r"'car_trailer'"):
        nonholo.plan([0.0, 0.0, 0.0], GOAL, mechanism=trailer)
    with pytest.raises(ValueError, match=r"^goal must be"):
        nonholo.plan(START, GOAL + [0.0], mechanism=trailer)
    assert main(["plan", "--mechanism", str(EXAMPLE), "--from", "0", "0", "0", "--to", *map(str, GOAL)]) == 2
    assert "--from takes 5 numbers for mechanism 'car_trailer' (x y theta phi theta1), got 3" in \
        capsys.readouterr().err


def test_plan_takes_a_file_where_it_takes_a_name(trailer):
    by_path = nonholo.plan(START, GOAL, mechanism=EXAMPLE, T=5.0, objective=None)
    by_text = nonholo.plan(START, GOAL, mechanism=str(EXAMPLE), T=5.0, objective=None)
    by_object = nonholo.plan(START, GOAL, mechanism=trailer, T=5.0, objective=None)
    assert by_path.success and by_path.mechanism == "car_trailer"
    assert by_path.kinematics is by_text.kinematics                 # built once per process
    assert np.allclose(by_path.q[-1], by_object.q[-1], atol=1e-9)
    with pytest.raises(ValueError, match=r"no_such\.toml"):
        nonholo.plan(START, GOAL, mechanism=EXAMPLE.parent / "no_such.toml")


@pytest.fixture(scope="module")
def cli_plan(tmp_path_factory):
    """``python -m nonholo.cli plan --mechanism FILE``, in a process of its own."""
    where = tmp_path_factory.mktemp("cli")
    out = where / "plan.json"
    run_ = subprocess.run([sys.executable, "-m", "nonholo.cli", "plan", "--mechanism", str(EXAMPLE), "--from",
                           *map(str, START), "--to", *map(str, GOAL), "--objective", "none", "--quiet",
                           "--out", str(out)], capture_output=True, text=True, timeout=600, cwd=where)
    return run_, out


@pytest.mark.slow
def test_the_command_line_plans_a_file_mechanism_and_its_plan_loads_alone(cli_plan, trailer):
    run_, out = cli_plan
    assert run_.returncode == 0, run_.stderr
    assert "success" in run_.stdout and "car_trailer" in run_.stdout
    d = json.loads(out.read_text())
    assert d["mechanism"] == "car_trailer"
    assert d["mechanism_digest"] == definition_forms.digest(trailer.definition)
    assert d["mechanism_definition"]["bounds"]["inputs"]["w"] == ["-inf", "inf"]   # JSON holds no inf
    res = PlanResult.load(out)                        # no mechanism= needed
    assert res.success and res.kinematics.definition == trailer.definition
    np.testing.assert_allclose(res.q[-1], GOAL, atol=1e-8)
    assert PlanResult.load(out, mechanism=trailer) == res


def test_a_bad_file_on_the_command_line_exits_2_naming_it(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(line(12, 'theta = "evil(w)"'))
    assert main(["plan", "--mechanism", str(path), "--from", "0", "0", "0", "--to", "1", "0", "0"]) == 2
    assert f"{path}, line 12, rates.theta: 'evil(w)' is not a call" in capsys.readouterr().err


@pytest.mark.slow
def test_execute_says_a_file_mechanism_has_no_physics_model(cli_plan, capsys):
    pytest.importorskip("mujoco")
    assert main(["execute", str(cli_plan[1])]) == 2
    assert "mechanism 'car_trailer' has no physics model" in capsys.readouterr().err


def test_a_changed_definition_or_digest_is_refused_naming_the_field(cli_plan, tmp_path):
    d = json.loads(cli_plan[1].read_text())
    path = tmp_path / "forged.json"

    def refused(data, match):
        path.write_text(json.dumps(data))
        with pytest.raises(ValueError, match=match):
            PlanResult.load(path)

    changed = json.loads(json.dumps(d))
    changed["mechanism_definition"]["parameters"]["d"] = 2.0
    refused(changed, r"'mechanism_digest' does not match 'mechanism_definition'")
    changed["mechanism_digest"] = "0" * 64
    refused(changed, r"'mechanism_digest' does not match")
    alone = {k: v for k, v in d.items() if k != "mechanism_digest"}
    refused(alone, r"'mechanism_digest' is missing")
    # a definition that is user data: checked as a file is, with a digest that matches
    evil = json.loads(json.dumps(d))
    evil["mechanism_definition"]["rates"]["x"] = f"__import__('os').system('touch {tmp_path / MARKER}')"
    evil["mechanism_digest"] = definition_forms.digest(evil["mechanism_definition"])
    refused(evil, r"'mechanism_definition.rates.x': .* is not a call of an allowed function")
    assert not (tmp_path / MARKER).exists()
    # a definition consistent with its digest, but other numbers: the replay refuses it
    other = json.loads(json.dumps(d))
    other["mechanism_definition"]["parameters"]["d"] = 0.5
    other["mechanism_digest"] = definition_forms.digest(other["mechanism_definition"])
    refused(other, r"invalid plan: 'q.*' disagrees with the controls")
    renamed = json.loads(json.dumps(d))
    renamed["mechanism_definition"]["name"] = "other_name"
    renamed["mechanism_digest"] = definition_forms.digest(renamed["mechanism_definition"])
    refused(renamed, r"'mechanism' is 'car_trailer', but 'mechanism_definition' defines 'other_name'")


def test_a_catalog_plan_carries_no_definition():
    res = nonholo.plan([0.0, 0.0, 0.0, 0.0], [0.2, 0.0, 0.0, 0.0], mechanism="car", objective=None)
    d = res.to_dict()
    assert "mechanism_definition" not in d and "mechanism_digest" not in d and d["mechanism"] == "car"


# -- sweeps and the atlas ------------------------------------------------------------------------

def test_a_sweep_table_names_a_file_relative_to_its_own_directory(tmp_path, monkeypatch, trailer):
    (tmp_path / "tables" / "mechs").mkdir(parents=True)
    trailer.to_file(tmp_path / "tables" / "mechs" / "trailer.toml")
    table = tmp_path / "tables" / "problems.jsonl"
    rows = [{"start": START, "goal": GOAL, "mechanism": "mechs/trailer.toml",
             "options": {"objective": None, "route": "local"}, "label": "trailer"},
            {"start": [0, 0, 0, 0], "goal": [0.2, 0, 0, 0], "mechanism": "car", "options": {"objective": None}}]
    table.write_text("".join(json.dumps(r) + "\n" for r in rows))
    monkeypatch.chdir(tmp_path)                      # not the table's directory
    checked = problems.read(table)
    assert checked[0]["mechanism"] == "car_trailer" and checked[0]["kinematics"].definition == trailer.definition
    # the workers are sent data: the definition, not a path nor a module
    sent = problems.as_json(checked[0])
    assert sent["mechanism"] == definition_forms.json_data(trailer.definition)
    assert problems.as_json(checked[1])["mechanism"] == "car"
    out = tmp_path / "results.parquet"
    result = sweep.sweep(str(table), out, workers=2, progress=False).to_pylist()
    assert [r["mechanism"] for r in result] == ["car_trailer", "car"]
    assert all(r["success"] and r["error"] is None for r in result), result
    plan = result_store.plan_of(result[0])                 # the row's plan loads alone
    assert plan.kinematics.definition == trailer.definition
    np.testing.assert_allclose(plan.q[-1], GOAL, atol=1e-8)
    # the same table read from elsewhere resolves the same file; a changed file is another table
    assert problems.fingerprint(problems.read(table)) == problems.fingerprint(checked)
    (tmp_path / "tables" / "mechs" / "trailer.toml").write_text(
        EXAMPLE.read_text().replace("d = 1.5", "d = 1.25"))
    assert problems.fingerprint(problems.read(table)) != problems.fingerprint(checked)


def test_a_bad_file_in_a_sweep_table_is_refused_naming_row_file_line_and_field(tmp_path, capsys):
    (tmp_path / "bad.toml").write_text(line(11, 'y = "v*sin(theta) + __import__(\'os\')"'))
    table = tmp_path / "p.jsonl"
    table.write_text(json.dumps({"start": [0, 0, 0], "goal": [1, 0, 0], "mechanism": "bad.toml"}) + "\n")
    want = f"problem row 0, column 'mechanism': {tmp_path / 'bad.toml'}, line 11, rates.y: "
    with pytest.raises(ValueError, match=re.escape(want)):
        problems.read(table)
    assert main(["sweep", str(table), "--out", str(tmp_path / "r.parquet"), "--quiet"]) == 2
    assert want in capsys.readouterr().err
    bad_definition = {"start": [0, 0, 0], "goal": [1, 0, 0],
                      "mechanism": {"name": "cart", "inputs": ["v"], "coordinates": ["x", "y", "theta"],
                                    "rates": {"x": "v", "y": "v", "theta": "open('f')"}}}
    with pytest.raises(ValueError, match=re.escape("problem row 0, column 'mechanism': mechanism.rates.theta: ")):
        problems.check([bad_definition])


def test_the_atlas_takes_a_mechanism_file(tmp_path, capsys):
    out = tmp_path / "atlas.jsonl"
    assert main(["atlas", "--problems", str(out), "--mechanism", str(EXAMPLE), "--grid", "2",
                 "--axes", "x", "y", "--start", *map(str, START), "--extent", "-1", "1", "-1", "1"]) == 0
    rows = problems.read(out)
    assert len(rows) == 4 * len(atlas.SETTINGS) and {r["mechanism"] for r in rows} == {"car_trailer"}
    assert rows[0]["kinematics"].definition == Mechanism.from_file(EXAMPLE).definition
    capsys.readouterr()
    bad = tmp_path / "bad.toml"
    bad.write_text(line(12, 'theta = "w*q7"'))
    assert main(["atlas", "--problems", str(out), "--mechanism", str(bad), "--grid", "2"]) == 2
    assert f"--mechanism refused: {bad}, line 12, rates.theta: " in capsys.readouterr().err


# -- the guide -------------------------------------------------------------------------------------

def test_the_guide_shows_the_example_file_and_lists_the_functions():
    from derivations import admission

    text = (ROOT / "docs" / "guide" / "mechanisms.md").read_text()
    assert "## A mechanism in one file" in text and "car_trailer.toml" in text
    for name in admission.FUNCTIONS:
        assert f"`{name}`" in text, name
    assert "--mechanism FILE" in (ROOT / "docs" / "guide" / "cli.md").read_text()
