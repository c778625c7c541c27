"""nonholo.motion."""
