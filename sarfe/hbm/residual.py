r"""Harmonic-balance residual and its analytic Jacobian, full or condensed to the contact rows.

Full (all kept DOFs, unknowns x = ũ.ravel(), (2H+1) n of them):

    R(ũ, ω) = S(ω) ũ + f̃_nl(ũ) − f̃_e,      f̃_nl = Gᵀ λ̃(G ũ)   (per harmonic)
    ∂R/∂ũ = S(ω) + (I⊗G)ᵀ ∂λ̃/∂r̃ (I⊗G)      (sparse),    ∂R/∂ω = (∂S/∂ω) ũ + (I⊗G)ᵀ ∂λ̃/∂ω

Condensed (unknowns x = r̃.ravel(), (2H+1) n_rows of them, see :mod:`sarfe.hbm.dynamic_stiffness`):

    R_c(r̃, ω) = r̃ − r̃_lin(ω) + C(ω) λ̃(r̃),    ∂R_c/∂r̃ = I + C ∂λ̃/∂r̃ (dense),
    ∂R_c/∂ω = G Z⁻¹ Z' ũ(r̃) + C ∂λ̃/∂ω

∂λ̃/∂ω = E diag(∂λ/∂ṙ) Φ ∇ r̃ comes from the rate-dependent laws through ṙ = ω ∇ r (zero, and
skipped, when every law is rate independent; :mod:`sarfe.hbm.aft`).

With a harmonic set (``Problem.harmonic_orders``, :mod:`sarfe.hbm.harmonic_set`) x holds only the
kept coefficient rows, and R, ∂R/∂x, ∂R/∂ω are the kept rows (and columns) of the above: the
Galerkin projection P_𝒦 R(P_𝒦ᵀ x). The AFT runs on all 2H+1 rows, the dropped ones zero; its
Jacobian blocks are built for the kept rows and columns only.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from sarfe.hbm.aft import ContactForces, contact_forces, jacobian_matrix
from sarfe.hbm.harmonic_set import coefficient_rows, expand_rows
from sarfe.hbm.dynamic_stiffness import (apply_dynamic_stiffness, apply_dynamic_stiffness_derivative,
                     condensed_omega_derivative, dynamic_stiffness_matrix, modal_omega_derivative,
                     recover_displacement)


@dataclass(frozen=True)
class Problem:
    """The data of one harmonic-balance problem: model (M, D, K), contacts, f̃_e (2H+1, n) [N], H, N;
    harmonic_orders: the kept orders of a harmonic set (sorted ints), None = all 0 … H."""

    model: object
    contacts: object
    excitation: np.ndarray
    harmonics: int
    samples_per_period: int
    friction_tolerance: float = 1e-12
    friction_pass_cap: int = 50
    harmonic_orders: np.ndarray = None


def kept_rows(problem: Problem):
    """Coefficient rows of the kept orders (sorted), or None when all rows are kept."""
    return None if problem.harmonic_orders is None else coefficient_rows(problem.harmonic_orders)


def _kept_indices(rows, width):
    """Flat indices (harmonic-major) of the kept rows of a (2H+1, width) array."""
    return (np.asarray(rows)[:, None] * width + np.arange(width)[None, :]).ravel()


@dataclass(frozen=True)
class Evaluation:
    """Residual R (P,), Jacobian ∂R/∂x (dense or sparse, or None), ∂R/∂ω (P,), forces, reference;
    unit_columns: indices of the columns of ∂R/∂x equal to unit vectors (condensed rows without
    contact stiffness, eliminated before the LU: :func:`sarfe.hbm.newton.solve_linear`), or None."""

    residual: np.ndarray
    jacobian: object
    omega_derivative: np.ndarray
    forces: ContactForces
    reference: float
    unit_columns: np.ndarray = None


def _gap_blocks(contacts, harmonics):
    return sp.kron(sp.identity(2 * harmonics + 1), contacts.gap_map, format="csr")


def nonlinear_force(contacts, U, samples_per_period, slider_start=None, jacobian=True, omega=None):
    """f̃_nl = Gᵀ λ̃(G ũ) (2H+1, n) [N], ∂f̃_nl/∂ũ (sparse, harmonic-major) and the ContactForces."""
    U = np.asarray(U, dtype=float)
    H = (U.shape[0] - 1) // 2
    G = contacts.gap_map
    R = np.asarray(G @ U.T).T
    forces = contact_forces(contacts, R, samples_per_period, slider_start, jacobian, omega=omega)
    f = np.asarray(G.T @ forces.force.T).T
    jac = None
    if jacobian:
        GG = _gap_blocks(contacts, H)
        jac = (GG.T @ jacobian_matrix(forces.blocks, G.shape[0], H) @ GG).tocsr()
    return f, jac, forces


def full_residual(problem: Problem, x, omega, slider_start=None, jacobian=True,
                  assemble=True) -> Evaluation:
    """R(ũ, ω) on all DOFs; x = ũ.ravel() (harmonic-major; kept rows only with a harmonic set).
    Reference ‖f̃_e‖. ``assemble=False`` (with ``jacobian``): the contact Jacobian blocks in
    ``forces`` only, ∂R/∂ũ and ∂R/∂ω not assembled (None)."""
    n = problem.model.dof_count
    rows = kept_rows(problem)
    U = expand_rows(x, rows, problem.harmonics, n)
    G = problem.contacts.gap_map
    forces = contact_forces(problem.contacts, np.asarray(G @ U.T).T, problem.samples_per_period,
                            slider_start, jacobian, problem.friction_tolerance,
                            problem.friction_pass_cap, rows, omega)
    f_nl = np.asarray(G.T @ forces.force.T).T
    R = apply_dynamic_stiffness(problem.model, omega, U) + f_nl - problem.excitation
    J = dR = None
    if jacobian and assemble:
        P = 2 * problem.harmonics + 1 if rows is None else rows.size
        GG = sp.kron(sp.identity(P), G, format="csr")
        J_nl = GG.T @ jacobian_matrix(forces.blocks, G.shape[0], problem.harmonics,
                                      kept_rows=rows) @ GG
        S = dynamic_stiffness_matrix(problem.model, omega, problem.harmonics)
        dR = apply_dynamic_stiffness_derivative(problem.model, omega, U).ravel()
        if forces.omega_derivative is not None:
            dR = dR + np.asarray(G.T @ forces.omega_derivative.T).T.ravel()
        if rows is not None:     # S is block diagonal over the harmonics: keep the kept blocks
            keep = _kept_indices(rows, n)
            S, dR = S[keep][:, keep], dR[keep]
        J = (S + J_nl).tocsc()
    if rows is not None:
        R = R[rows]
    return Evaluation(R.ravel(), J, dR, forces, _reference(np.linalg.norm(problem.excitation)))


DENSE_CONTACT_JACOBIAN = 4000   # ∂λ̃/∂r̃ kept sparse above this many rows (J itself is dense)


def condensed_residual(problem: Problem, condensation, x, slider_start=None,
                       jacobian=True, omega_derivative=True) -> Evaluation:
    """R_c(r̃, ω) at the ω of ``condensation``; x = r̃.ravel() (kept rows only with a harmonic set;
    the condensation must then hold the same orders). Reference ‖r̃_lin‖.

    C is block diagonal over the harmonics, so C ∂λ̃/∂r̃ is formed block row by block row
    (:meth:`sarfe.hbm.dynamic_stiffness.Condensation.apply_compliance`: O(P n_rows · P) instead of O(P³)).
    ``omega_derivative`` False (Newton at a fixed ω): ∂R_c/∂ω is not formed (None)."""
    n_rows = problem.contacts.row_count
    rows = kept_rows(problem)
    Rr = expand_rows(x, rows, problem.harmonics, n_rows)
    forces = contact_forces(problem.contacts, Rr, problem.samples_per_period, slider_start,
                            jacobian, problem.friction_tolerance, problem.friction_pass_cap, rows,
                            condensation.omega)
    keep = None if rows is None else _kept_indices(rows, n_rows)
    force = forces.force.ravel() if keep is None else forces.force.ravel()[keep]
    r_lin = condensation.linear_response.ravel()
    C = condensation.compliance
    R = x - (r_lin if keep is None else r_lin[keep]) + C @ force
    J = dR = None
    if jacobian:
        if x.size <= DENSE_CONTACT_JACOBIAN:     # assembled dense (no sparse detour)
            J_lam = jacobian_matrix(forces.blocks, n_rows, problem.harmonics, dense=True,
                                    kept_rows=rows)
            unit = np.flatnonzero(~J_lam.any(axis=0))       # rows without contact stiffness
        else:                                              # (stored entries may be zeros)
            J_lam = jacobian_matrix(forces.blocks, n_rows, problem.harmonics, kept_rows=rows)
            unit = np.flatnonzero(abs(J_lam).sum(axis=0).A1 == 0)
        J = condensation.apply_compliance(J_lam)
        J[np.diag_indices_from(J)] += 1.0
        if omega_derivative:
            if condensation.modal is not None:      # from λ̃ in modal coordinates (no ũ)
                dR = modal_omega_derivative(condensation, forces.force).ravel()
            else:
                U = recover_displacement(condensation, forces.force)
                dR = condensed_omega_derivative(problem.model, condensation, U).ravel()
            if keep is not None:
                dR = dR[keep]
            if forces.omega_derivative is not None:
                rate = forces.omega_derivative.ravel()
                dR = dR + C @ (rate if keep is None else rate[keep])
    reference = _reference(np.linalg.norm(condensation.linear_response), np.linalg.norm(x))
    return Evaluation(R, J, dR, forces, reference, unit if jacobian else None)


def _reference(*values):
    value = max(values)
    return value if value > 0 else 1.0
