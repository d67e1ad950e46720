"""sarfe.reduction — Craig–Bampton reduction of (K, M), its mode searches, recovery.

- craig_bampton.py: ``craig_bampton`` (partition, Ψ = −K_ii⁻¹ K_ib, residual modes, projection).
- reduced_model.py: ``ReducedModel`` (M_r, K_r, D_r, T's interior rows), ``with_modal_damping``,
  ``with_rayleigh_damping``, and the DOF numbering ``free_dofs_system``, ``free_dof_positions``,
  ``node_dofs``.
- fixed_interface_modes.py: the mode search K_ii φ = ω² M_ii φ (block Lanczos, capped run 0 +
  spectrum slicing in one or two processes, ARPACK fallback), on
  lanczos.py (block shift-invert Lanczos), spectrum_slicing.py (shifted runs certified by
  inertia counts), arpack_modes.py (``eigsh``), mode_sinks.py (found vectors in memory or on disk).
- recovery.py: ``recover_displacement`` (u = T q), ``normal_velocity_basis`` (ṽ_n = iω N q̃).
- ``factorize`` and the sparse solvers are sarfe/linalg.py's (re-exported here).
"""
from sarfe.linalg import Factorization, available_solvers, choose_solver, factorize
from sarfe.reduction.craig_bampton import craig_bampton
from sarfe.reduction.recovery import dof_rows, normal_velocity_basis, recover_displacement
from sarfe.reduction.reduced_model import (ReducedModel, free_dof_positions, free_dofs_system, node_dofs,
                                           with_modal_damping, with_rayleigh_damping)

__all__ = [
    "Factorization", "factorize", "available_solvers", "choose_solver",
    "ReducedModel", "craig_bampton", "free_dofs_system", "free_dof_positions", "node_dofs",
    "recover_displacement", "dof_rows", "normal_velocity_basis",
    "with_modal_damping", "with_rayleigh_damping",
]
