"""``python -m imageform`` runs the command-line tool."""

import sys

from imageform.cli import main

try:
    code = main()
except KeyboardInterrupt:  # a signal that landed after main() had handled the first one
    print("imageform: interrupted; nothing new was written", file=sys.stderr)
    code = 130
sys.exit(code)
