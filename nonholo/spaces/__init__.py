"""State spaces: the state value, the factors and their product, the singular set, numeric
rotations."""
from .factors import SO3, Axis, Euclidean, FixedRotation
from .product import Product
from .singular import NoSingularSet, SingularSet
from .state import State

__all__ = ["State", "Product", "SO3", "Euclidean", "FixedRotation", "Axis", "SingularSet", "NoSingularSet"]
