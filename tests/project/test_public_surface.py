"""The public surface: ``nonholo.__all__``, and no name of the former flat layout left."""
import inspect

import pytest

import nonholo


def test_every_public_name_exists():
    for name in nonholo.__all__:
        assert getattr(nonholo, name) is not None, name


@pytest.mark.parametrize("old", ["so3", "verify", "planner", "result", "figures", "sweep", "limits"])
def test_the_former_flat_layout_is_gone(old):
    with pytest.raises(AttributeError, match=f"no attribute '{old}'"):
        getattr(nonholo, old)


def test_the_door_takes_at_most_twelve_parameters():
    """``plan`` takes the problem's parts; the numbers go in one ``Settings``, the
    constraints in a list of objects."""
    assert len(inspect.signature(nonholo.plan).parameters) <= 12
    assert len(inspect.signature(nonholo.Problem.build).parameters) <= 12
    assert len(inspect.getdoc(nonholo.plan).splitlines()) <= 40
