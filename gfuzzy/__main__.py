"""``python -m gfuzzy`` is the same program as ``gfuzzy``."""

import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main())
