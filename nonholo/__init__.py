"""nonholo: motion planning of non-holonomic systems on SO(3).

The numeric kinematics come from generated modules (``nonholo.generated``, written by
``nonholo derive`` from the SymPy derivations in ``derivations/``).
"""
__version__ = "0.1.0"
