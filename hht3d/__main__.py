"""``python -m hht3d`` is the ``hht3d`` command."""
import sys

from .cli import main

sys.exit(main())
