r"""From reduced coordinates q = [q_b, q_m] back to physical fields.

u = T q with T = [[I, 0], [Ψ, Φ]] (rows ordered as the free-DOF vector):
u_b = q_b, u_i = [Ψ, Φ] q. For harmonic motion u(t) = Re(ũ e^{iωt}) the surface-normal velocity at
a node is ṽ_n = iω nᵀ ũ_trans, so ERP needs only the (n_nodes, n_r) map  N = nᵀ T_trans  from
:func:`normal_velocity_basis`, then ṽ_n = iω N q̃ for each harmonic.
"""
from __future__ import annotations

import numpy as np

from sarfe.reduction.reduced_model import ReducedModel, free_dof_positions


def recover_displacement(reduced: ReducedModel, q, all_dofs: bool = False) -> np.ndarray:
    """u = T q for q (..., n_r) real or complex (leading axes e.g. harmonics or time samples).

    Returns (..., full_dof_count) on the free DOFs, or with ``all_dofs`` (..., total_dof_count) on
    the original DOF numbering with zeros at fixed DOFs (needs ``reduced.free_dofs``).
    """
    q = np.asarray(q)
    if q.shape[-1] != reduced.reduced_dof_count:
        raise ValueError(f"q must end with n_r = {reduced.reduced_dof_count}, got shape {q.shape}")
    u = np.zeros(q.shape[:-1] + (reduced.full_dof_count,), dtype=np.result_type(q, float))
    u[..., reduced.boundary_dofs] = q[..., : reduced.boundary_count]
    u[..., reduced.interior_dofs] = q @ reduced.interior_basis.T
    if not all_dofs:
        return u
    if reduced.free_dofs is None:
        return u
    total = reduced.total_dof_count or int(reduced.free_dofs.max() + 1)
    full = np.zeros(q.shape[:-1] + (total,), dtype=u.dtype)
    full[..., reduced.free_dofs] = u
    return full


def dof_rows(reduced: ReducedModel, free_positions) -> np.ndarray:
    """Rows of T (len(free_positions), n_r) for the given free-DOF positions."""
    free_positions = np.asarray(free_positions, dtype=int)
    rows = np.zeros((len(free_positions), reduced.reduced_dof_count))
    where_boundary = np.full(reduced.full_dof_count, -1, dtype=int)
    where_boundary[reduced.boundary_dofs] = np.arange(reduced.boundary_count)
    where_interior = np.full(reduced.full_dof_count, -1, dtype=int)
    where_interior[reduced.interior_dofs] = np.arange(len(reduced.interior_dofs))
    b = where_boundary[free_positions]
    i = where_interior[free_positions]
    rows[np.flatnonzero(b >= 0), b[b >= 0]] = 1.0
    rows[i >= 0] = reduced.interior_basis[i[i >= 0]]
    return rows


def normal_velocity_basis(reduced: ReducedModel, node_normals, nodes=None, dofs_per_node: int = 6) -> np.ndarray:
    """N (n_nodes, n_r) with nᵀ u_trans(node) = N q; surface-normal velocity ṽ_n = iω N q̃.

    node_normals: (n_nodes, 3) unit normals (one row per entry of ``nodes``); nodes: (n_nodes,)
    node numbers in the original mesh (default: 0..n_nodes-1). Translations are the original DOFs
    dofs_per_node*node + [0, 1, 2]; fixed DOFs (not in ``reduced.free_dofs``) contribute zero.
    """
    normals = np.asarray(node_normals, dtype=float)
    nodes = np.arange(len(normals)) if nodes is None else np.asarray(nodes, dtype=int)
    if normals.shape != (len(nodes), 3):
        raise ValueError(f"node_normals must have shape ({len(nodes)}, 3), got {normals.shape}")
    dofs = (dofs_per_node * nodes[:, None] + np.arange(3)[None, :]).ravel()
    if reduced.free_dofs is None:
        positions = dofs
        free = dofs < reduced.full_dof_count
    else:
        total = reduced.total_dof_count or int(reduced.free_dofs.max() + 1)
        position = np.full(max(total, dofs.max(initial=-1) + 1), -1, dtype=int)
        position[reduced.free_dofs] = np.arange(len(reduced.free_dofs))
        positions = position[dofs]
        free = positions >= 0
    # one translation component at a time: (n_nodes, n_r) rows, not (3 n_nodes, n_r) at once
    positions, free = positions.reshape(len(nodes), 3), free.reshape(len(nodes), 3)
    out = np.zeros((len(nodes), reduced.reduced_dof_count))
    for c in range(3):
        rows = np.zeros_like(out)
        rows[free[:, c]] = dof_rows(reduced, positions[free[:, c], c])
        out += normals[:, c:c + 1] * rows
    return out


__all__ = ["recover_displacement", "dof_rows", "normal_velocity_basis", "free_dof_positions"]
