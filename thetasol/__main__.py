"""``python -m thetasol``: the command line of :mod:`thetasol.scenes.cli`."""
import sys

from thetasol.scenes.cli import main

sys.exit(main())
