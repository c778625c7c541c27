"""State spaces: the state value, the factors and their product, the singular set, numeric
rotations."""
from .axes import Axis
from .euclidean import Euclidean
from .product import Product
from .rotation_factors import SO3, FixedRotation
from .singular import NoSingularSet, SingularSet
from .state import State

__all__ = ["State", "Product", "SO3", "Euclidean", "FixedRotation", "Axis", "SingularSet", "NoSingularSet"]
