"""``python -m sarfe`` = the ``sarfe`` command."""
import sys

from sarfe.cli import main

sys.exit(main())
