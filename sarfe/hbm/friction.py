"""The Jenkins friction element moved to :mod:`sarfe.hbm.laws.jenkins` (one module per law);
this name is kept for existing imports."""
from .laws.jenkins import (SEPARATED, SLIP, STICK, compose_clamps, jenkins_periodic_1d,  # noqa: F401
                           last_reset_index, slider_update, slider_update_derivatives)
