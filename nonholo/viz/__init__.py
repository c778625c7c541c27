"""nonholo.viz."""
