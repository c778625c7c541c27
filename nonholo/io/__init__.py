"""nonholo.io."""
