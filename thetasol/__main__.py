"""``python -m thetasol``: the command line of :mod:`thetasol.cli`."""
import sys

from thetasol.cli import main

sys.exit(main())
