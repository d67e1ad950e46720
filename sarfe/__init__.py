"""sarfe — squeak and rattle noise of vehicle interior panels.

Pipeline: mesh → fe → reduction (Craig–Bampton) → hbm (harmonic balance + AFT contact) → erp → io/cli.
SI units everywhere inside.
"""
import os as _os

# One BLAS thread per process unless the user says otherwise: on 2 shared cores oversubscribed
# BLAS threads made a harmonic-balance run 75x slower (shared/FACTS.md).
for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    _os.environ.setdefault(_name, "1")

__version__ = "0.1.0"
