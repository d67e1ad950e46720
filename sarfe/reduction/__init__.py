"""sarfe.reduction — sparse factorizations, Craig–Bampton reduction, recovery, reduced damping.

``factorize`` (sarfe/linalg.py), ``craig_bampton`` / ``ReducedModel`` / ``free_dofs_system``
(craig_bampton.py; its mode searches run the block Lanczos of lanczos.py, spectrum slicing of
spectrum_slicing.py, or ARPACK in arpack_modes.py), ``recover_displacement`` /
``normal_velocity_basis`` (recovery.py), ``reduced_modal_damping`` (damping.py).
"""
from sarfe.reduction.craig_bampton import ReducedModel, craig_bampton, free_dof_positions, free_dofs_system, node_dofs
from sarfe.reduction.damping import reduced_modal_damping, with_modal_damping, with_rayleigh_damping
from sarfe.linalg import Factorization, available_solvers, choose_solver, factorize
from sarfe.reduction.recovery import dof_rows, normal_velocity_basis, recover_displacement

__all__ = [
    "Factorization", "factorize", "available_solvers", "choose_solver",
    "ReducedModel", "craig_bampton", "free_dofs_system", "free_dof_positions", "node_dofs",
    "recover_displacement", "dof_rows", "normal_velocity_basis",
    "reduced_modal_damping", "with_modal_damping", "with_rayleigh_damping",
]
