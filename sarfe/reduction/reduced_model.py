r"""The reduced model record and the DOF numbering it is stated in.

A Craig–Bampton model (:func:`sarfe.reduction.craig_bampton.craig_bampton`) lives on
q = [q_b (n_b, physical boundary DOFs), q_m (n_m, fixed-interface modes), q_r (n_rv, residual
modes)] with M_r [kg], K_r [N/m] and, once damped, D_r [N s/m]:

- :class:`ReducedModel`: M_r, K_r, D_r and the interior rows [Ψ, Φ, Φ_r] of T (u = T q);
- :func:`with_modal_damping`: D_r = M_r X diag(2 ζ_j ω_j) Xᵀ M_r from K_r x_j = ω_j² M_r x_j,
  Xᵀ M_r X = I, every mode of the reduced model (boundary DOFs free) with ratio ζ_j, rigid-body
  modes undamped (the formula is :func:`sarfe.fe.damping.modal_damping`'s);
- :func:`with_rayleigh_damping`: D_r = α M_r + β K_r (= Tᵀ (α M + β K) T exactly);
- DOF numbering: :func:`free_dofs_system` removes clamped DOFs, :func:`free_dof_positions` maps
  original DOF numbers to positions in the free-DOF vector, :func:`node_dofs` lists a node's DOFs.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from sarfe.fe.damping import modal_damping


@dataclass(frozen=True, eq=False)  # array fields: compare explicitly, not with ==
class ReducedModel:
    """Craig–Bampton model on q = [q_b, q_m] (n_r = n_b + n_m).

    mass, stiffness: (n_r, n_r) dense [kg], [N/m]; damping: (n_r, n_r) [N s/m] or None.
    boundary_dofs: (n_b,) positions of the boundary DOFs in the free-DOF vector (length
    ``full_dof_count``); interior_dofs: (n_i,) the others, in increasing order.
    interior_basis: (n_i, n_r) = [Ψ, Φ], the interior rows of T (u_i = interior_basis @ q).
    mode_frequencies_hz: (n_m,) fixed-interface natural frequencies; residual_frequencies_hz:
    (n_rv,) Ritz frequencies of the residual modes (after the fixed-interface modes in q).
    free_dofs: (full_dof_count,) original (unconstrained) DOF number of each free DOF, or None if the
    free-DOF vector is the original one; total_dof_count: length of the original DOF vector.
    timings: wall seconds per stage (partition, factorization, constraint_modes, normal_modes,
    projection), the same with suffix "_cpu" in CPU seconds, and operator_applications (K_ii⁻¹ columns).
    """

    mass: np.ndarray
    stiffness: np.ndarray
    boundary_dofs: np.ndarray
    interior_dofs: np.ndarray
    interior_basis: np.ndarray
    mode_frequencies_hz: np.ndarray
    full_dof_count: int
    damping: np.ndarray | None = None
    free_dofs: np.ndarray | None = None
    total_dof_count: int | None = None
    solver: str = ""
    timings: dict = field(default_factory=dict, compare=False)
    residual_frequencies_hz: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def boundary_count(self) -> int:
        return len(self.boundary_dofs)

    @property
    def mode_count(self) -> int:
        return len(self.mode_frequencies_hz)

    @property
    def residual_vector_count(self) -> int:
        return len(self.residual_frequencies_hz)

    @property
    def reduced_dof_count(self) -> int:
        return self.boundary_count + self.mode_count + self.residual_vector_count

    @property
    def constraint_modes(self) -> np.ndarray:
        """Ψ (n_i, n_b): interior response to unit boundary displacements."""
        return self.interior_basis[:, : self.boundary_count]

    @property
    def fixed_interface_modes(self) -> np.ndarray:
        """Φ (n_i, n_m), mass-normalized on M_ii."""
        return self.interior_basis[:, self.boundary_count:self.boundary_count + self.mode_count]

    @property
    def residual_modes(self) -> np.ndarray:
        """Φ_r (n_i, n_rv): residual modes (module docstring), mass-normalized, M- and K-orthogonal to Φ."""
        return self.interior_basis[:, self.boundary_count + self.mode_count:]

    @property
    def size_reduction(self) -> dict:
        """Free DOFs, reduced DOFs, boundary DOFs, modes and the ratio free/reduced."""
        return {"free_dofs": self.full_dof_count, "reduced_dofs": self.reduced_dof_count,
                "boundary_dofs": self.boundary_count, "modes": self.mode_count,
                "residual_vectors": self.residual_vector_count,
                "ratio": self.full_dof_count / max(self.reduced_dof_count, 1)}


def free_dofs_system(stiffness, mass, fixed_dofs):
    """Remove fixed (clamped) DOFs: K_ff, M_ff (CSR) and free_dofs (n_f,) original DOF numbers.

    fixed_dofs: original DOF numbers held at zero (duplicates allowed).
    """
    n = stiffness.shape[0]
    keep = np.ones(n, dtype=bool)
    keep[np.asarray(fixed_dofs, dtype=int)] = False
    free = np.flatnonzero(keep)
    stiffness, mass = sp.csr_matrix(stiffness), sp.csr_matrix(mass)
    return stiffness[free][:, free].tocsr(), mass[free][:, free].tocsr(), free


def free_dof_positions(dofs, free_dofs, total_dof_count=None):
    """Positions in the free-DOF vector of original DOF numbers ``dofs``. Raises if one is fixed."""
    dofs = np.asarray(dofs, dtype=int)
    if free_dofs is None:
        return dofs
    total = int(total_dof_count if total_dof_count is not None else free_dofs.max() + 1)
    position = np.full(max(total, dofs.max(initial=-1) + 1), -1, dtype=int)
    position[free_dofs] = np.arange(len(free_dofs))
    out = position[dofs]
    if np.any(out < 0):
        raise ValueError(f"DOFs {dofs[out < 0][:5].tolist()} are fixed, not free")
    return out


def node_dofs(nodes, components=(0, 1, 2), dofs_per_node: int = 6) -> np.ndarray:
    """Original DOF numbers dofs_per_node*node + component, node-major, e.g. translations only."""
    nodes = np.asarray(nodes, dtype=int)
    return (dofs_per_node * nodes[:, None] + np.asarray(components, dtype=int)[None, :]).ravel()



def with_modal_damping(reduced: ReducedModel, zeta) -> ReducedModel:
    """A copy of ``reduced`` with D_r = M_r X diag(2 ζ_j ω_j) Xᵀ M_r (module docstring).

    zeta: ζ [-], scalar or (n_r,) per mode of (K_r, M_r) in ascending ω.
    """
    return dataclasses.replace(reduced, damping=modal_damping(reduced.mass, reduced.stiffness, zeta))


def with_rayleigh_damping(reduced: ReducedModel, alpha: float, beta: float) -> ReducedModel:
    """A copy with D_r = α M_r + β K_r (= Tᵀ (α M + β K) T exactly) [α 1/s, β s]."""
    return dataclasses.replace(reduced, damping=alpha * reduced.mass + beta * reduced.stiffness)
