"""``python -m imageform.cli``."""

import sys

from imageform.cli import main

sys.exit(main())
