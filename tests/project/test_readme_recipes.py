"""The README's "Adding a mechanism" runs as printed: each of its Python blocks is executed
on its own, and the plan it makes is confirmed by SciPy's DOP853 on a model written out here
(the platform: its constraint matrix from the block's geometry in NumPy; the trailer: its
rates by hand), not on the generated code."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from nonholo.spaces import so3

README = Path(__file__).resolve().parents[2] / "README.md"


def section_blocks(title: str = "Adding a mechanism") -> list[str]:
    """The ```python blocks of the README's section ``## title``."""
    text = README.read_text()
    start = text.index(f"\n## {title}\n")
    end = text.find("\n## ", start + 1)
    return re.findall(r"```python\n(.*?)```", text[start:end if end > 0 else None], flags=re.S)


BLOCKS = section_blocks()


def test_the_section_has_its_two_recipes():
    assert len(BLOCKS) == 2
    assert "PlatformGeometry" in BLOCKS[0] and "from_constraints" in BLOCKS[1]


@pytest.fixture(scope="module")
def ran():
    """Each block executed in a namespace of its own."""
    out = []
    for block in BLOCKS:
        namespace = {"__name__": "readme"}
        exec(compile(block, "README.md", "exec"), namespace)
        out.append(namespace)
    return out


@pytest.mark.slow
def test_the_platform_recipe_plans_what_its_geometry_moves(ran):
    ns = ran[0]
    result, g = ns["result"], ns["geometry"]
    assert result.success, result.reason
    vec = {k: np.array(getattr(g, k), dtype=float) for k in ("base1", "tip1", "base2", "tip2", "contact", "axle")}
    disk = np.cross(vec["contact"], vec["axle"])

    def omega(R, u):
        """``C(R) ω = (u₁, u₂, 0)``: leg rows ``-2 (R tip × base) / (4 |base| |tip|)``, the disk's row."""
        rows = [-2 * np.cross(R @ vec[f"tip{i}"], vec[f"base{i}"])
                / (4 * np.linalg.norm(vec[f"base{i}"]) * np.linalg.norm(vec[f"tip{i}"])) for i in (1, 2)]
        return np.linalg.solve(np.array(rows + [disk]), [u[0], u[1], 0.0])

    def f(t, y):
        R = y.reshape(3, 3)
        return (so3.hat(omega(R, result.controls(np.array([t]))[0])) @ R).ravel()

    sol = solve_ivp(f, (0.0, result.T), ns["R0"].ravel(), method="DOP853", rtol=1e-12, atol=1e-12,
                    t_eval=[result.T])
    assert so3.distance(sol.y[:, -1].reshape(3, 3), ns["Rd"]) < 1e-8


@pytest.mark.slow
def test_the_vehicle_recipe_plans_what_its_constraints_allow(ran):
    ns = ran[1]
    result = ns["result"]
    assert result.success, result.reason
    assert ns["trailer"].state_space == "R^4" and ns["trailer"].delta is None
    d = 1.0

    def f(t, q):
        v, w = result.controls(np.array([t]))[0]
        return [v * np.cos(q[2]), v * np.sin(q[2]), w, v * np.sin(q[2] - q[3]) / d]

    sol = solve_ivp(f, (0.0, result.T), np.zeros(4), method="DOP853", rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(sol.y[:, -1], [1.0, 0.5, 0.0, 0.0], atol=1e-8)
