"""``python -m emulator`` = ``tm-emulator``."""

import sys

from .cli import main

sys.exit(main())
