"""Generated numeric modules against their symbolic source, and the derivations' claims."""
import shutil

import numpy as np
import pytest
import sympy as sp
from conftest import SO3_MECHANISMS
from conftest import random_rotations as _random_rotations

from derivations import codegen, definitions, singularity
from derivations.mechanisms import PAPER_GEOMETRY, constraint_matrix, paper_platform
from derivations.rotations import r
from derivations.variational import Q_matrix, inputs
from nonholo.generated import platform_singularity as gen_sing
from nonholo.model import catalog as numeric
from nonholo.spaces import so3

RNG = np.random.default_rng(2014)
N_POINTS = 120


def random_rotations(n, min_abs_delta=0.05):
    """Random rotations away from the platform's Δ = 0 (where L and Q are undefined)."""
    return _random_rotations(n, RNG, min_abs_delta)


def _mp(expr_list, args):
    """mpmath evaluation of SymPy expressions: independent of the generated printer."""
    return sp.lambdify(args, expr_list, modules="mpmath")


@pytest.mark.parametrize("name", SO3_MECHANISMS)
def test_generated_matches_symbolic(name):
    sym = definitions.get(name)
    num = numeric.get(name)
    u = inputs(sym.n_inputs)
    f_L = _mp(list(sym.L), list(r))
    f_Q = _mp(list(Q_matrix(sym.L, u)), list(r) + list(u))
    f_d = _mp(sym.delta, list(r)) if sym.delta is not None else None
    worst = 0.0
    for R in random_rotations(N_POINTS):
        uu = RNG.normal(size=sym.n_inputs)
        pairs = [(num.L(R).ravel(), np.array(f_L(*R.ravel()), dtype=float)),
                 (num.Q(R, uu).ravel(), np.array(f_Q(*R.ravel(), *uu), dtype=float))]
        if f_d is not None:
            assert num.delta is not None
            pairs.append((np.array([num.delta(R)]), np.array([float(f_d(*R.ravel()))])))
        for got, want in pairs:
            worst = max(worst, np.max(np.abs(got - want)) / max(1.0, np.max(np.abs(want))))
    assert worst < 1e-12


@pytest.mark.parametrize("name", SO3_MECHANISMS)
def test_Q_is_derivative_of_L_along_left_variations(name):
    num = numeric.get(name)
    eps = 1e-6
    for R in random_rotations(20, min_abs_delta=0.2):
        u = RNG.normal(size=num.n_inputs)
        s = RNG.normal(size=3)
        fd = (num.L(so3.exp(eps * s) @ R) @ u - num.L(so3.exp(-eps * s) @ R) @ u) / (2 * eps)
        np.testing.assert_allclose(num.Q(R, u) @ s, fd, rtol=1e-7, atol=1e-7 * np.abs(fd).max())


def test_delta_is_constraint_determinant_up_to_derived_constant():
    m = paper_platform()
    kappa = float(m.derivation["kappa"])
    C = sp.lambdify(list(r), constraint_matrix(PAPER_GEOMETRY).subs({}), "numpy")
    num = numeric.get("platform")
    for R in random_rotations(50):
        assert np.linalg.det(np.array(C(*R.ravel()), dtype=float)) == pytest.approx(
            kappa * num.delta(R), rel=1e-12, abs=1e-15)
    assert m.delta == r[0, 1] * r[2, 0] + r[1, 0] * r[2, 1]


def test_L_solves_the_constraint_equations():
    C = sp.lambdify(list(r), constraint_matrix(PAPER_GEOMETRY), "numpy")
    num = numeric.get("platform")
    for R in random_rotations(30):
        CR = np.array(C(*R.ravel()), dtype=float)
        np.testing.assert_allclose(CR @ num.L(R), [[1, 0], [0, 1], [0, 0]], atol=1e-12)


def test_normal_form_identity_at_small_angles():
    for _ in range(200):
        phi, theta, psi = RNG.uniform(-0.3, 0.3, size=3)
        x, y, z = gen_sing.normal_form(phi, theta, psi)
        d = gen_sing.delta_rpy(phi, theta, psi)
        assert z**3 + x * y == pytest.approx(d, rel=1e-10, abs=1e-15)
        assert d == pytest.approx(numeric.get("platform").delta(so3.from_rpy(phi, theta, psi)),
                                  rel=1e-10, abs=1e-15)


def test_normal_form_coordinates_are_local_coordinates():
    # numerical Jacobian at 0 against the symbolic one (determinant ±1)
    h = 1e-6
    J = np.column_stack([(np.array(gen_sing.normal_form(*(h * e))) -
                          np.array(gen_sing.normal_form(*(-h * e)))) / (2 * h) for e in np.eye(3)])
    J_sym = np.array(singularity.coordinate_jacobian_at_zero(), dtype=float)
    np.testing.assert_allclose(J, J_sym, atol=1e-8)
    assert abs(np.linalg.det(J_sym)) == 1.0


def test_attitude_A_vanishes():
    """For dR/dt = R[u1 e1 + u2 e2], A = Q + [Lu] = 0 identically (issue 6)."""
    from derivations.variational import variational_system
    V = variational_system(definitions.get("attitude"))
    assert V["A"].applyfunc(sp.expand).is_zero_matrix


@pytest.mark.slow
def test_derive_check_passes_on_committed_tree(capsys):
    from nonholo.cli.entry import main
    assert main(["derive", "--check"]) == 0


@pytest.mark.slow
def test_derive_check_fails_on_altered_copy(tmp_path, capsys):
    from nonholo.cli.entry import main
    copy = tmp_path / "generated"
    shutil.copytree(codegen.GENERATED_DIR, copy)
    target = copy / "platform.py"
    target.write_text(target.read_text().replace("2/(", "2.0000001/(", 1))
    assert main(["derive", "--check", "--dir", str(copy)]) == 1
    assert "platform.py" in capsys.readouterr().err
    (copy / "platform.py").unlink()
    shutil.copy(codegen.GENERATED_DIR / "platform.py", copy / "platform.py")
    assert main(["derive", "--check", "--dir", str(copy)]) == 0


def test_codegen_is_deterministic():
    assert codegen.generated_files() == codegen.generated_files()


def test_paper_instance_gives_the_papers_L():
    """The general platform derivation at the paper's geometry gives the paper's L(R)."""
    m = definitions.get("platform")
    D = r[0, 1] * r[2, 0] + r[1, 0] * r[2, 1]
    L_paper = 2 / D * sp.Matrix([[r[1, 0], r[0, 1]], [-r[1, 0], -r[0, 1]], [-r[2, 0], r[2, 1]]])
    assert (m.L - L_paper).applyfunc(sp.cancel).is_zero_matrix
    f = sp.lambdify(list(r), L_paper, "numpy")
    num = numeric.get("platform")
    for R in random_rotations(50):
        np.testing.assert_allclose(num.L(R), np.array(f(*R.ravel()), dtype=float),
                                   rtol=1e-14, atol=1e-14 * np.abs(num.L(R)).max())


def test_raised_platform_is_regular_at_identity_and_splits_SO3():
    num = numeric.get("platform_raised")
    assert num.delta(np.eye(3)) == pytest.approx(1.0)
    values = np.array([num.delta(R) for R in random_rotations(400, min_abs_delta=0.0)])
    assert (values > 0.05).any() and (values < -0.05).any()


@pytest.mark.parametrize("name", SO3_MECHANISMS)
def test_desingularised_frame(name):
    """ω = N(R) w with N orthonormal; u = W(R) w reproduces it (L W = N); W is finite
    everywhere (polynomial in r_ij); QN is the derivative of N along left variations."""
    sym = definitions.get(name)
    num = numeric.get(name)
    assert num.has_frame
    gen = num.frame                 # N, QN, W of the desingularised frame
    W_sym = sym.frame_inputs if sym.frame_inputs is not None else \
        __import__("derivations.mechanisms", fromlist=["input_map"]).input_map(sym.L, sym.frame)
    assert all(sp.denom(sp.cancel(w)).free_symbols == set() for w in W_sym)
    f_N = _mp(list(sym.frame), list(r))
    eps = 1e-6
    for R in random_rotations(30):
        N = gen.N(R)
        np.testing.assert_allclose(N.T @ N, np.eye(2), atol=1e-14)
        np.testing.assert_allclose(N, np.array(f_N(*R.ravel()), dtype=float).reshape(3, 2), atol=1e-14)
        np.testing.assert_allclose(num.L(R) @ gen.W(R), N, atol=1e-11)
        w, s = RNG.normal(size=2), RNG.normal(size=3)
        fd = (gen.N(so3.exp(eps * s) @ R) @ w - gen.N(so3.exp(-eps * s) @ R) @ w) / (2 * eps)
        np.testing.assert_allclose(gen.QN(R, w) @ s, fd, atol=1e-8)
