"""A platform's geometry is checked when it is made: the sphere's radius is 1 (the unit of
length), so the disk's contact point and the legs' platform joints lie on the unit sphere
and the disk's axle is tangent to it at the contact point. An impossible geometry is
refused with ``ValueError`` naming the field and its defect as measured, before anything
is derived; the catalog's platforms and the README's pass.

The defects are measured here independently (NumPy on the vectors given), and the message
must quote them.
"""
from __future__ import annotations

import re

import numpy as np
import pytest
import sympy as sp

from derivations import definitions, mechanisms
from derivations.mechanisms import (
    GEOMETRY_TOL,
    PAPER_GEOMETRY,
    PlatformGeometry,
    a,
    b,
    check_geometry,
    platform_mechanism,
    rho,
)
from derivations.rotations import e1, e2, e3

#: A valid geometry of numbers: the README's (the disk off the pole, the bases raised).
GOOD = dict(base1=(0.0, 1.6, 0.5), tip1=(0.0, 1.0, 0.0), base2=(1.6, 0.0, 0.5), tip2=(1.0, 0.0, 0.0),
            contact=(0.6, 0.0, 0.8), axle=(0.0, 1.0, 0.0))


def number_in(message: str, after: str) -> float:
    """The number the message gives right after ``after``."""
    found = re.search(re.escape(after) + r"\s*(-?[0-9.]+(?:e[-+]?[0-9]+)?)", message)
    assert found, f"no number after {after!r} in {message!r}"
    return float(found.group(1))


def refused(**changes) -> str:
    with pytest.raises(ValueError) as caught:
        PlatformGeometry(**{**GOOD, **changes})
    return str(caught.value)


def test_the_good_geometry_passes_and_derives():
    m = platform_mechanism("good_geometry", PlatformGeometry(**GOOD), "the README's platform")
    assert m.delta is not None and m.L.shape == (3, 2)


@pytest.mark.parametrize("contact", [(0.0, 0.0, 0.92), (0.6, 0.0, 0.9), (0.0, 0.0, 1.0 + 1e-7), (0.0, 0.0, 2.0)])
def test_a_contact_point_off_the_sphere_is_refused_with_its_distance(contact):
    message = refused(contact=contact, axle=(0.0, 1.0, 0.0))
    assert message.startswith("geometry: contact: |contact| = ")
    assert "expected 1" in message
    measured = number_in(message, "|contact| =")
    assert measured == pytest.approx(np.linalg.norm(contact), rel=1e-3)
    assert measured != 1.0                       # enough digits to see the defect


def test_the_example_of_the_issue():
    message = refused(contact=(0.0, 0.0, 0.92), axle=(0.0, 1.0, 0.0))
    assert "contact: |contact| = 0.92, expected 1" in message


@pytest.mark.parametrize("axle", [(0.31, 0.0, 0.95), (0.0, 1.0, 0.1), (1.0, 1.0, 1.0), (0.0, 0.0, 1.0)])
def test_an_axle_not_tangent_is_refused_with_its_cosine(axle):
    contact = np.array(GOOD["contact"])
    message = refused(axle=axle)
    assert message.startswith("geometry: axle: axle·contact/(|axle| |contact|) = ")
    assert "expected 0 (the axle is tangent to the sphere at the contact point)" in message
    cosine = float(np.dot(axle, contact) / (np.linalg.norm(axle) * np.linalg.norm(contact)))
    assert number_in(message, "axle·contact/(|axle| |contact|) =") == pytest.approx(cosine, rel=1e-3)


def test_an_axle_of_no_length_is_refused():
    assert "axle: |axle| = 0, expected a direction" in refused(axle=(0, 0, 0))


@pytest.mark.parametrize("key", ["tip1", "tip2"])
@pytest.mark.parametrize("tip", [(0.1, 1.0, 0.0), (0.0, 0.8, 0.1), (1.0, 0.0, 1e-4), (0.5, 0.5, 0.5)])
def test_a_platform_joint_off_the_sphere_is_refused_with_its_distance(key, tip):
    message = refused(**{key: tip})
    assert message.startswith(f"geometry: {key}: |{key}| = ")
    assert "expected the sphere's radius 1" in message
    assert number_in(message, f"|{key}| =") == pytest.approx(np.linalg.norm(tip), rel=1e-3)


def test_the_tip_of_the_issue():
    assert "tip1: |tip1| = 1.005, expected the sphere's radius 1" in refused(tip1=(0.1, 1.0, 0.0))


def test_the_tolerance_is_relative_and_tight():
    """Within ``GEOMETRY_TOL`` of the sphere is on it (floats normalised by NumPy are); a
    thousand times that is not."""
    assert GEOMETRY_TOL <= 1e-9
    for v in [(0.1, 1.0, 0.0), (0.021, 0.804, 0.113), (-2.3, -0.2, -1.2)]:
        u = tuple(float(x) for x in np.array(v) / np.linalg.norm(v))
        PlatformGeometry(**{**GOOD, "tip1": u, "tip2": u})
    off = 1.0 + 1000 * GEOMETRY_TOL
    assert "tip2: |tip2| = 1.000001" in refused(tip2=(off, 0.0, 0.0))
    PlatformGeometry(**{**GOOD, "tip2": (1.0 + 0.1 * GEOMETRY_TOL, 0.0, 0.0)})


def test_a_symbolic_geometry_is_measured_at_the_dimensions():
    """The paper's symbols are measured at a = 8/5, b = ρ = 1 (the numbers the generated code
    uses), and the message says so; a symbol of another name cannot be measured."""
    g = PAPER_GEOMETRY
    check_geometry(g)
    with pytest.raises(ValueError, match=r"tip1: \|tip1\| = 1\.6, expected the sphere's radius 1 .*"
                                         r"measured at a = 8/5, b = rho = 1"):
        PlatformGeometry(base1=g.base1, tip1=tuple(a * e2), base2=g.base2, tip2=g.tip2,
                         contact=g.contact, axle=g.axle)
    with pytest.raises(ValueError, match=r"contact: \|contact\| = 2, expected 1"):
        PlatformGeometry(base1=g.base1, tip1=g.tip1, base2=g.base2, tip2=g.tip2,
                         contact=tuple(2 * rho * e3), axle=g.axle)
    x = sp.Symbol("x")
    with pytest.raises(ValueError, match=r"geometry: tip2\[0\] = x has the symbol x"):
        PlatformGeometry(base1=g.base1, tip1=g.tip1, base2=g.base2, tip2=(x, 0, 0),
                         contact=g.contact, axle=g.axle)
    # the axle's check uses the direction: a symbolic multiple of a tangent axle is tangent
    PlatformGeometry(base1=g.base1, tip1=g.tip1, base2=g.base2, tip2=g.tip2, contact=g.contact,
                     axle=tuple(b * (e1 - e2)))


def test_the_catalog_platforms_pass():
    checked = []
    for name, make in definitions.MECHANISMS.items():
        geometry = make().derivation.get("geometry")
        if geometry is None:
            continue
        check_geometry(geometry)
        checked.append(name)
    assert {"platform", "platform_raised"} <= set(checked)


def test_a_geometry_changed_behind_its_checks_is_refused_before_the_derivation(monkeypatch):
    """A geometry mutated past ``__post_init__`` is refused by the mechanism's own checks
    (``check_definition``), and by ``platform_mechanism`` before anything is derived."""
    g = PlatformGeometry(**GOOD)
    object.__setattr__(g, "tip1", (0.0, 1.2, 0.0))
    derived = []
    monkeypatch.setattr(mechanisms, "exact_platform", lambda *args: derived.append(args))
    with pytest.raises(ValueError, match=r"tip1: \|tip1\| = 1\.2"):
        platform_mechanism("mutated", g, "a tip moved after the checks")
    assert not derived


def test_an_impossible_geometry_no_longer_plans():
    """Before, a contact point inside the sphere built, planned and returned success=True;
    now it is refused when the geometry is made."""
    with pytest.raises(ValueError, match=r"geometry: contact: \|contact\| = 0\.5, expected 1"):
        PlatformGeometry(**{**GOOD, "contact": (0.3, 0.0, 0.4)})
