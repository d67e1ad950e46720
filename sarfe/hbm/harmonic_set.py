r"""Harmonic sets: solve for a subset of the harmonic orders 0 … H (e.g. odd orders only).

A harmonic set 𝒦 ⊂ {0, 1, …, H} keeps the coefficient rows of its orders (row 0 for k = 0, rows
2k−1, 2k for k ≥ 1, see :mod:`sarfe.hbm.harmonics`); the others are held at zero. The equations are
the Galerkin projection of the full harmonic balance onto the kept rows,

    R_𝒦(ũ_𝒦, ω) = P_𝒦 [ S(ω) ũ + f̃_nl(ũ) − f̃_e ] = 0,      ũ = P_𝒦ᵀ ũ_𝒦,

with P_𝒦 selecting the kept rows. S(ω) is block diagonal over the harmonics, so the projection
drops whole blocks of the linear part (and of the dynamic compliance G Z_k⁻¹ Gᵀ when condensed);
the AFT still samples the whole period with all 2H+1 rows (the dropped ones zero), so the contact
forces are exact for the kept displacement.

A symmetric system — f_nl(−u) = −f_nl(u) (e.g. a mass between two identical gaps, a Jenkins
element without normal preload), no mean load and a harmonic drive — has a solution with only odd
orders (u(θ + π) = −u(θ)); then the odd set {1, 3, 5, …} gives the same solution as the full set
with about half the unknowns. A one-sided (rattle) contact breaks the symmetry: its force has a mean
and even harmonics, and the odd set is wrong.

Estimate of what the dropped orders carry (one AFT, done at every solution by :func:`dropped_content`):

    η = ‖f̃_nl,d(ũ) − f̃_e,d‖ / (‖f̃_e‖ + ‖f̃_nl(ũ)‖)       (d = dropped rows, all DOFs)

At a reduced solution ũ_d = 0, so η is the residual of the dropped equations relative to the
forces in the balance; at a full-set solution it is ‖S_d ũ_d‖ / (…), the force the dropped orders
carry. η = 0 for a symmetric system (to solver tolerance). ``harmonic_set='auto'`` solves the odd
set, and re-solves with the full set when η exceeds ``SolverOptions.harmonic_set_tolerance``
(see :mod:`sarfe.hbm.solve`).
"""
from __future__ import annotations

import numpy as np

__all__ = ["harmonic_set_orders", "coefficient_rows", "expand_rows", "dropped_content",
           "AUTO_CANDIDATE"]

AUTO_CANDIDATE = "odd"   # the reduced set 'auto' tries first


def harmonic_set_orders(harmonic_set, harmonics: int):
    """Kept orders (sorted int array) of a harmonic set, or None when it keeps all of 0 … H.

    harmonic_set: None | 'all' | 'odd' ({1, 3, 5, …} ≤ H, no mean) | a sequence of orders
    (0 ≤ k ≤ H, at least one k ≥ 1). 'auto' is resolved by the solver, not here.
    Raises ValueError naming the parameter.
    """
    H = int(harmonics)
    if harmonic_set is None or (isinstance(harmonic_set, str) and harmonic_set == "all"):
        return None
    if isinstance(harmonic_set, str):
        if harmonic_set != "odd":
            raise ValueError(f"harmonic_set must be None, 'all', 'odd', 'auto' or a list of "
                             f"orders, got {harmonic_set!r}")
        orders = np.arange(1, H + 1, 2)
    else:
        raw = np.asarray(harmonic_set).ravel()
        if raw.size == 0 or not np.all(np.mod(raw, 1) == 0):
            raise ValueError(f"harmonic_set orders must be integers, got {harmonic_set!r}")
        orders = np.unique(raw.astype(int))
        if orders.min() < 0 or orders.max() > H:
            raise ValueError(f"harmonic_set orders must lie in 0 … H = {H}, got {orders.tolist()}")
        if orders.max() < 1:
            raise ValueError("harmonic_set must keep at least one order k >= 1")
    return None if orders.size == H + 1 else orders


def coefficient_rows(orders) -> np.ndarray:
    """Rows of U (2H+1, …) of the kept orders, sorted: k = 0 → [0], k ≥ 1 → [2k−1, 2k]."""
    orders = np.asarray(orders, dtype=int)
    rows = np.concatenate([[0]] * bool(np.any(orders == 0)) + [
        np.stack([2 * orders[orders > 0] - 1, 2 * orders[orders > 0]], axis=1).ravel()])
    return np.sort(rows.astype(int))


def expand_rows(x, rows, harmonics: int, width: int) -> np.ndarray:
    """P_𝒦ᵀ: kept coefficients x (len(rows)·width,) → U (2H+1, width), dropped rows zero.

    rows None means all rows (a reshape)."""
    x = np.asarray(x, dtype=float)
    if rows is None:
        return x.reshape(-1, width)
    U = np.zeros((2 * int(harmonics) + 1, width))
    U[rows] = x.reshape(len(rows), width)
    return U


def dropped_content(nonlinear_force, excitation, kept_rows) -> float:
    """η = ‖f̃_nl,d − f̃_e,d‖ / (‖f̃_e‖ + ‖f̃_nl‖) over the rows not in ``kept_rows`` (see module
    docstring); f̃_nl, f̃_e (2H+1, n) [N]. 0 when nothing is dropped."""
    F_nl, F_e = np.asarray(nonlinear_force, dtype=float), np.asarray(excitation, dtype=float)
    dropped = np.setdiff1d(np.arange(F_e.shape[0]), kept_rows)
    if dropped.size == 0:
        return 0.0
    scale = np.linalg.norm(F_e) + np.linalg.norm(F_nl)
    if scale == 0:
        return 0.0
    return float(np.linalg.norm(F_nl[dropped] - F_e[dropped]) / scale)
