"""nonholo.paper."""
