"""nonholo.model."""
