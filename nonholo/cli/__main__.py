"""``python -m nonholo.cli``: the command line (as the ``nonholo`` script)."""
import sys

from .entry import main

sys.exit(main())
