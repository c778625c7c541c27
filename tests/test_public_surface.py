"""The public surface: ``nonholo.__all__`` and the former flat layout's module names, kept
for one release as aliases that warn."""
import importlib

import pytest

import nonholo


def test_every_public_name_exists():
    for name in nonholo.__all__:
        assert getattr(nonholo, name) is not None, name


@pytest.mark.parametrize("old", sorted(nonholo.MOVED))
def test_an_old_module_name_warns_and_is_the_moved_module(old):
    with pytest.warns(DeprecationWarning, match=f"nonholo.{old} is now nonholo.{nonholo.MOVED[old]}"):
        module = getattr(nonholo, old)
    assert module is importlib.import_module(f"nonholo.{nonholo.MOVED[old]}")


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'nosuch'"):
        nonholo.nosuch  # noqa: B018
