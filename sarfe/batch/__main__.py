"""``python -m sarfe.batch …`` = ``sarfe batch …``."""
import sys

from sarfe.batch.cli import main

sys.exit(main())
