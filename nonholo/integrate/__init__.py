"""nonholo.integrate."""
