"""``python -m nonholo``: the command line (as the ``nonholo`` script)."""
import sys

from .cli.entry import main

sys.exit(main())
