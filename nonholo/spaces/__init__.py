"""nonholo.spaces."""
