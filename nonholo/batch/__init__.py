"""nonholo.batch."""
