"""nonholo.certify."""
