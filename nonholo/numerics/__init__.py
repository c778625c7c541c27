"""nonholo.numerics."""
