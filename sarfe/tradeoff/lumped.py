r"""Small lumped stand-in problems for studies, stability grids and benchmarks (SI units).

A chain of n masses m on springs k to ground and k_c between neighbours, modal-free viscous damping
D = 2 ζ √(k m) I (ζ may be 0). Contacts (grounded, one row each):

- rattle on DOF i: w = u_i, λ = k_n max(0, u_i − g)  (``penalty_ratio`` = k_n / k);
- squeak on DOF i: tangential q = u_i, Jenkins k_t with μ and a constant normal load N0.

The force f_e = F cos ωt acts on DOF 0 (or on all DOFs with ``force_all``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.model import make_linear_model


@dataclass(frozen=True)
class LumpedProblem:
    model: object
    contacts: object
    excitation: np.ndarray     # (2H+1, n) [N] for the H it was built with
    natural_frequencies_rad_s: np.ndarray
    description: str


def lumped_problem(n_masses=1, *, mass=1.0, stiffness=1.0e4, coupling=None, zeta=0.02,
                   rattle_dofs=(0,), gap=1e-3, penalty_ratio=10.0, squeak_dofs=(),
                   friction_coefficient=0.3, normal_load=1.0, tangential_ratio=10.0, force=10.0,
                   harmonics=5, force_all=False) -> LumpedProblem:
    """Build the chain (module docstring). gap: scalar or one per rattle DOF [m]."""
    n = int(n_masses)
    kc = stiffness if coupling is None else coupling
    K = np.diag(np.full(n, float(stiffness)))
    for i in range(n - 1):
        K[i, i] += kc
        K[i + 1, i + 1] += kc
        K[i, i + 1] -= kc
        K[i + 1, i] -= kc
    M = np.eye(n) * mass
    D = 2.0 * zeta * np.sqrt(stiffness * mass) * np.eye(n)
    model = make_linear_model(M, D, K)
    rows, kind, normal, tangent, gaps, kn, kt, mu, n0, names = [], [], [], [], [], [], [], [], [], []
    gap_values = np.broadcast_to(np.asarray(gap, dtype=float), (len(rattle_dofs),))
    for j, dof in enumerate(rattle_dofs):
        row = np.zeros(n)
        row[dof] = 1.0
        rows.append(row)
        kind.append("rattle")
        normal.append(len(rows) - 1)
        tangent.append([-1, -1])
        gaps.append(gap_values[j])
        kn.append(penalty_ratio * stiffness)
        kt.append(0.0)
        mu.append(0.0)
        n0.append(0.0)
        names.append(f"rattle_{dof}")
    for dof in squeak_dofs:
        row = np.zeros(n)
        row[dof] = 1.0
        rows.append(row)
        kind.append("squeak")
        normal.append(-1)
        tangent.append([len(rows) - 1, -1])
        gaps.append(0.0)
        kn.append(0.0)
        kt.append(tangential_ratio * stiffness)
        mu.append(friction_coefficient)
        n0.append(normal_load)
        names.append(f"squeak_{dof}")
    G = sp.csr_matrix(np.array(rows).reshape(len(rows), n))
    contacts = make_contact_set(G, np.array(kind, dtype=object), np.array(normal, dtype=int),
                                np.array(tangent, dtype=int).reshape(-1, 2), gaps, kn, kt, mu, n0,
                                names)
    F = np.zeros((2 * harmonics + 1, n))
    if force_all:
        F[1] = force
    else:
        F[1, 0] = force
    w = np.sqrt(np.linalg.eigvalsh(np.linalg.solve(M, K)))
    text = (f"{n}-mass chain, {len(rattle_dofs)} rattle, {len(squeak_dofs)} squeak, ζ={zeta:g}, "
            f"k_n/k={penalty_ratio:g}, F={force:g} N")
    return LumpedProblem(model, contacts, F, np.sort(w), text)


__all__ = ["LumpedProblem", "lumped_problem"]
