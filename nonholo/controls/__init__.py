"""nonholo.controls."""
