r"""Modal damping on a reduced model.

Solve the reduced eigenproblem K_r x_j = ω_j² M_r x_j with X ᵀ M_r X = I and set

    D_r = M_r X diag(2 ζ_j ω_j) Xᵀ M_r       [N s/m]

so that every mode of the reduced model (boundary DOFs free) has damping ratio ζ_j. Zero-frequency
(rigid-body) modes get no damping. The formula is ``sarfe.fe.damping.modal_damping``'s (fe is below
reduction): applied here to the reduced matrices.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from sarfe.fe.damping import modal_damping

from sarfe.reduction.craig_bampton import ReducedModel


def reduced_modal_damping(mass, stiffness, zeta) -> np.ndarray:
    """D_r (n_r, n_r) from dense M_r [kg], K_r [N/m] and ζ (scalar or (n_r,), ascending modes)."""
    return modal_damping(mass, stiffness, zeta)


def with_modal_damping(reduced: ReducedModel, zeta) -> ReducedModel:
    """A copy of ``reduced`` with D_r = :func:`reduced_modal_damping` (M_r, K_r, ζ)."""
    return dataclasses.replace(reduced, damping=reduced_modal_damping(reduced.mass, reduced.stiffness, zeta))


def with_rayleigh_damping(reduced: ReducedModel, alpha: float, beta: float) -> ReducedModel:
    """A copy with D_r = α M_r + β K_r (= Tᵀ (α M + β K) T exactly) [α 1/s, β s]."""
    return dataclasses.replace(reduced, damping=alpha * reduced.mass + beta * reduced.stiffness)
