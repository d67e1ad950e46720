"""sarfe.fe — finite-element matrices.

Flat facet shell triangles (Allman membrane + DKT bending + drilling penalty, 6 DOF per
node) for the trim panels, a scikit-fem quadratic solid for chunky parts and reference
checks, support DOF sets and linear damping.
"""

from sarfe.fe.assembly import assemble, assemble_pair, element_dofs, fixed_dofs, free_dofs
from sarfe.fe.damping import modal_damping, rayleigh_damping
from sarfe.fe.modes import natural_frequencies
from sarfe.fe.shell import local_frames, shell_element_matrices, shell_matrices

__all__ = [
    "shell_matrices",
    "shell_element_matrices",
    "local_frames",
    "assemble",
    "assemble_pair",
    "natural_frequencies",
    "element_dofs",
    "fixed_dofs",
    "free_dofs",
    "rayleigh_damping",
    "modal_damping",
]
