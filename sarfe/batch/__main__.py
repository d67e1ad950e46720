"""``python -m sarfe.batch …`` = ``sarfe batch …``."""
import sys

from sarfe.batch.cli import main

if __name__ == "__main__":  # guarded: Dask's spawned workers import the main module again
    sys.exit(main())
