r"""ERP of reduced coordinates as a quadratic form: the radiating-surface sums without the nodal field.

With the radiating-node normal displacements w = N u of reduced coordinates u (N: (n_s, n), the
stage's ``erp_map``) and lumped nodal areas A_i, every area-weighted sum the ERP needs is

    Σ_i A_i w̄_a,i w_b,i = u_aᴴ Q u_b,        Q = Nᵀ diag(A) N     (n × n, real symmetric) [m²],

so once Q is built (O(n_s n²), once per model) a point's ERP costs O(H n²) whatever the size of the
radiating surface; P_k = ½ρc·RLF (kω)² (u_kcᵀ Q u_kc + u_ksᵀ Q u_ks) (:mod:`sarfe.erp.erp`).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["radiation_gram", "harmonic_power_proxy"]

_GRAM: dict = {}    # the Gram matrix of the last (erp_map, areas): every point of a run shares it


def radiation_gram(erp_map, areas) -> np.ndarray:
    """Q = Nᵀ diag(A) N (n, n) [m²] of the radiating normal-displacement map N (n_s, n) (dense or
    sparse) and the nodal areas A (n_s,) [m²]; cached for the last (N, A) objects passed."""
    key = (id(erp_map), id(areas))
    hit = _GRAM.get(key)
    if hit is not None and hit[0] is erp_map and hit[1] is areas:
        return hit[2]
    A = np.asarray(areas, dtype=float)
    if sp.issparse(erp_map):
        Q = np.asarray((erp_map.T @ sp.diags(A) @ erp_map).todense())
    else:
        N = np.asarray(erp_map, dtype=float)
        Q = N.T @ (A[:, None] * N)
    Q = 0.5 * (Q + Q.T)
    _GRAM.clear()
    _GRAM[key] = (erp_map, areas, Q)
    return Q


def harmonic_power_proxy(U, omega: float, gram) -> np.ndarray:
    """p_k = (kω)² (u_kcᵀ Q u_kc + u_ksᵀ Q u_ks) (H,) [m⁴/s²] of harmonic coefficients U (2H+1, n)
    [m] (sarfe convention): Σ_i A_i |v_i,k|², the ERP of harmonic k over ½ρc·RLF."""
    U = np.asarray(U, dtype=float)
    X = U[1:]
    rows = np.einsum("rn,rn->r", X, X @ gram)
    H = (U.shape[0] - 1) // 2
    return ((np.arange(1, H + 1) * float(omega)) ** 2) * (rows[0::2] + rows[1::2])
