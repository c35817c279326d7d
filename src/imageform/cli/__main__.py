"""``python -m imageform.cli``."""

import sys

from imageform.cli import main

sys.exit(main())  # main() handles Ctrl-C and SIGTERM itself (exit 130)
