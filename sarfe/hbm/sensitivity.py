r"""Sensitivity of a scalar of a converged periodic solution to the contact parameters, by one
adjoint solve with the converged harmonic-balance Jacobian (no re-solve).

For the balance R(ũ, p) = S(ω) ũ + Gᵀ λ̃(G ũ; p) − f̃_e = 0 and a scalar J(ũ) (e.g. the A-weighted
ERP level, :mod:`sarfe.erp.level_sensitivity`) the implicit function theorem gives

    dJ/dp = ∂J/∂p − ηᵀ ∂R/∂p,    (∂R/∂ũ)ᵀ η = (∂J/∂ũ)ᵀ,    ∂R/∂p = (I⊗G)ᵀ ∂λ̃/∂p.

Only the contact forces depend on a contact parameter p (gap g, k_n, k_t, μ, N0, …), so with the
*force adjoint* m = −(I⊗G) η (2H+1, n_rows) every parameter costs one inner product,

    dJ/dp_c = ⟨m, ∂λ̃/∂p_c⟩ = Σ_h Σ_{rows r of c} m_hr ∂λ̃_hr/∂p_c.

Condensed system (the default, as Newton solves it: :mod:`sarfe.hbm.residual`). The unknowns
are the contact rows r̃, R_c(r̃, p) = r̃ − r̃_lin + C λ̃(r̃; p) = 0 with J_c = I + C Λ,
Λ = ∂λ̃/∂r̃, and the DOFs follow from the recovery ũ = y − Y λ̃ (per order k:
ũ_k = Z_k⁻¹(f_k − Gᵀ λ_k)). Carrying
∂J/∂ũ through the recovery gives g = ∂J/∂λ̃ (:func:`recovery_gradient`) and

    J_cᵀ ζ = Λᵀ g,      m = g − Cᵀ ζ                     (dense LU of P_c = P n_rows rows),

the same m as the full system (the push-through identity (I + ΛC)⁻¹ = I − Λ(I + CΛ)⁻¹C), at the
cost of one Newton step of the condensed solver. The full system (P n unknowns, sparse LU of
(∂R/∂ũ)ᵀ) is the fallback where a Z_k(ω) is singular, and the check of the condensed path.
With a harmonic set (``solution.harmonic_orders``) both work on the kept rows, as Newton did.

∂λ̃/∂p_c: the laws declare no parameter derivatives, so it is the central difference of the AFT
force evaluation alone at the converged r̃ (:func:`force_parameter_derivatives`; a forward one at a
parameter's declared lower bound) — two force evaluations per parameter name, all contacts at once
(the force of a contact depends on its own parameters only), no re-solve. Step h_c = 10⁻⁶ |p_c|
(gap: 10⁻⁶ max(|g|, ½ ptp w)): the force is piecewise smooth in p, so h must be small against the
distance of the nearest sample from a stick/slip or open/closed switch.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from sarfe.hbm import laws
from sarfe.hbm.aft import contact_forces, jacobian_matrix
from sarfe.hbm.dynamic_stiffness import condense, from_complex, to_complex
from sarfe.hbm.newton import SingularJacobian, solve_linear
from sarfe.hbm.residual import (DENSE_CONTACT_JACOBIAN, condensed_residual, full_residual,
                                kept_rows)
from sarfe.hbm.solve import make_problem

__all__ = ["Sensitivities", "PARAMETERS", "RELATIVE_STEP", "contact_of_rows",
           "force_parameter_derivatives", "recovery_gradient", "force_adjoint",
           "adjoint_sensitivities"]

PARAMETERS = ("gap", "normal_stiffness", "tangential_stiffness", "friction_coefficient",
              "normal_load")
"""Parameters differentiated by default: the gap (ContactSet.gap) and the laws' scalar parameters
of these names (each law declares which it uses)."""

RELATIVE_STEP = 1e-6


@dataclass(frozen=True)
class Sensitivities:
    """dJ/dp of one point. derivative {name: (n_c,)} [unit of J per unit of p] (NaN where the
    contact's law or rows do not use p); step {name: (n_c,)} the difference step of ∂λ̃/∂p;
    force_adjoint m (2H+1, n_rows) [unit of J per N] (dJ/dp = ⟨m, ∂λ̃/∂p⟩ for any further p; zero
    in dropped rows); method 'condensed' | 'full' | 'singular' (:func:`force_adjoint`: then NaN)."""

    derivative: dict
    step: dict
    force_adjoint: np.ndarray
    method: str

    def per_relative_change(self, contacts) -> dict:
        """{name: p dJ/dp (n_c,)} [unit of J]: the change of J per relative change of p (×0.1
        gives the change for +10 %)."""
        values = {"gap": contacts.gap}
        return {name: values[name] * d if name in values else contacts.parameters[name] * d
                for name, d in self.derivative.items()}


def contact_of_rows(contacts) -> np.ndarray:
    """(n_rows,) int: the contact that owns each row of G (normal or tangent), −1 for none.
    Raises ValueError when two contacts share a row."""
    owner = np.full(contacts.row_count, -1)
    index = np.arange(contacts.count)
    rows = np.concatenate([contacts.normal_row, contacts.tangent_rows[:, 0],
                           contacts.tangent_rows[:, 1]])
    who = np.concatenate([index, index, index])
    used = rows >= 0
    if np.unique(rows[used]).size != np.count_nonzero(used):
        raise ValueError("two contacts share a row of the gap map: per-contact sensitivities need "
                         "rows of their own")
    owner[rows[used]] = who[used]
    return owner


def _uses(contacts, name) -> np.ndarray:
    """(n_c,) bool: the contact's law declares ``name`` and the contact has the rows it acts on."""
    has_normal = contacts.normal_row >= 0
    has_tangent = contacts.tangent_rows[:, 0] >= 0
    if name == "gap":
        return has_normal.copy()
    uses = np.zeros(contacts.count, bool)
    for contact_law, idx, _ in laws.groups(contacts):
        declared = {p.name: p for p in contact_law.parameters}
        if name not in declared:
            continue
        p = declared[name]
        ok = np.ones(idx.size, bool)
        if p.normal_part:
            ok &= has_normal[idx]
        tangent_names = {q.name for q in getattr(contact_law.tangent, "PARAMETERS", ())}
        if p.tangent_part or name in tangent_names:
            ok &= has_tangent[idx]
        uses[idx] = ok
    return uses


def _with_parameter(contacts, name, values):
    if name == "gap":
        return replace(contacts, gap=values)
    return replace(contacts, parameters={**contacts.parameters, name: values})


def force_parameter_derivatives(contacts, contact_displacement, samples_per_period, omega=None,
                                names=PARAMETERS, relative_step=RELATIVE_STEP) -> dict:
    r"""{name: (∂λ̃/∂p (2H+1, n_rows) [N per unit of p], uses (n_c,) bool, step h (n_c,))}.

    Column block of contact c: ∂λ̃/∂p_c on c's own rows, by the difference
    (λ̃(r̃; p + h) − λ̃(r̃; p − h)) / 2h of the AFT force evaluation
    (:func:`sarfe.hbm.aft.contact_forces`, no Jacobian) with every contact that uses p perturbed
    at once by its own h_c (module docstring); forward (λ̃(p + h) − λ̃(p))/h where p − h would
    pass the parameter's declared lower bound. r̃ (2H+1, n_rows) [m]; ω [rad/s] (rate-dependent
    laws). A name no contact uses (or a tabulated, non-scalar parameter) is left out."""
    R = np.asarray(contact_displacement, dtype=float)
    N = int(samples_per_period)
    declared = laws.all_parameters()
    has_normal = contacts.normal_row >= 0
    w = R[:, np.maximum(contacts.normal_row, 0)]
    swing = np.where(has_normal, 0.5 * (np.abs(w[1:]).sum(axis=0)), 0.0)   # ≥ ½ ptp w
    owner = contact_of_rows(contacts)
    out = {}
    for name in names:
        uses = _uses(contacts, name)
        value = contacts.gap if name == "gap" else contacts.parameters.get(name)
        if value is None or np.ndim(value) != 1 or not np.any(uses):
            continue
        value = np.asarray(value, dtype=float)
        scale = np.maximum(np.abs(value), swing) if name == "gap" else np.abs(value)
        step = relative_step * np.where(scale > 0, scale, 1.0) * uses
        lower = -np.inf
        p = declared.get(name)
        if p is not None and p.minimum is not None:
            lower = p.minimum
        forward = (value - step < lower) | ((value - step == lower) & bool(p and p.exclusive))
        minus = np.where(forward, value, value - step)
        plus = value + step

        forces = [contact_forces(_with_parameter(contacts, name, v), R, N, jacobian=False,
                                 omega=omega).force for v in (plus, minus)]
        width = np.where(uses, plus - minus, 1.0)
        spread = np.where(owner >= 0, width[np.maximum(owner, 0)], 1.0)
        out[name] = ((forces[0] - forces[1]) / spread, uses, np.where(uses, step, np.nan))
    return out


def recovery_gradient(condensation, displacement_gradient) -> np.ndarray:
    r"""g = ∂J/∂λ̃ (2H+1, n_rows) through the recovery ũ_k = y_k − Y_k λ̃_k (kept orders k) of a
    gradient ∂J/∂ũ (2H+1, n) (sarfe convention).

    With γ_k = ∂J/∂u_kc − i ∂J/∂u_ks (dJ = Re Σ_k γ̄_kᵀ dz_k for z_k = u_kc − i u_ks) and
    v_k = Y_kᵀ γ̄_k = G Z_k⁻¹ γ̄_k: ∂J/∂λ_kc = −Re v_k, ∂J/∂λ_ks = −Im v_k (dropped orders 0)."""
    grad = np.asarray(displacement_gradient, dtype=float)
    H = (grad.shape[0] - 1) // 2
    orders = np.arange(H + 1) if condensation.orders is None else np.asarray(condensation.orders)
    v = condensation.apply_admittance_transpose(np.conj(to_complex(grad)[orders]))
    out = np.zeros((H + 1, v.shape[1]), dtype=complex)
    out[orders] = -np.conj(v)
    return from_complex(out)


def _kept(X, rows):
    X = np.asarray(X)
    return X if rows is None else X[rows]


def force_adjoint(model, contacts, excitation, solution, objective_gradient,
                  condensed=True):
    """(m (2H+1, n_rows), method): the force adjoint of the converged ``solution`` (a
    HarmonicSolution of ``model``, ``contacts``, f̃_e = ``excitation``) for ∂J/∂ũ =
    ``objective_gradient`` (2H+1, n) — module docstring. ``condensed``: on the contact rows
    (falling back to the full system where a Z_k(ω) or J_c is singular), else on all DOFs.
    method 'condensed' | 'full' | 'singular' (m NaN: the Jacobian is singular to working
    precision, e.g. at a fold of the branch, where dJ/dp is unbounded)."""
    H, N, omega = solution.harmonics, solution.samples_per_period, float(solution.omega)
    orders = solution.harmonic_orders
    problem = make_problem(model, contacts, excitation, H, N,
                           harmonic_set=None if orders is None else list(orders))
    rows = kept_rows(problem)
    G = sp.csr_matrix(contacts.gap_map)
    U = np.asarray(solution.displacement, dtype=float)
    grad = np.asarray(objective_gradient, dtype=float)
    n_rows = G.shape[0]
    m = np.full((2 * H + 1, n_rows), np.nan)
    kept, method = None, "singular"
    condensation = condense(model, G, problem.excitation, omega, problem.harmonic_orders) \
        if condensed else None
    if condensation is not None:
        x = _kept(np.asarray(G @ U.T).T, rows).ravel()
        ev = condensed_residual(problem, condensation, x, jacobian=True, omega_derivative=False)
        Lam = jacobian_matrix(ev.forces.blocks, n_rows, H,
                              dense=x.size <= DENSE_CONTACT_JACOBIAN, kept_rows=rows)
        g = _kept(recovery_gradient(condensation, grad), rows).ravel()
        try:                                                 # J_cᵀ ζ = Λᵀ g
            zeta = solve_linear(np.ascontiguousarray(ev.jacobian.T), Lam.T @ g)
            kept, method = g - condensation.compliance.T @ zeta, "condensed"
        except SingularJacobian:
            pass
    if kept is None:
        ev = full_residual(problem, _kept(U, rows).ravel(), omega, jacobian=True)
        try:                                                 # (∂R/∂ũ)ᵀ η = ∂J/∂ũ
            eta = solve_linear(sp.csc_matrix(ev.jacobian.T), _kept(grad, rows).ravel())
            kept, method = -np.asarray(G @ eta.reshape(-1, U.shape[1]).T).T, "full"
        except SingularJacobian:
            return m, method
    m[:] = 0.0
    m[slice(None) if rows is None else rows] = np.asarray(kept).reshape(-1, n_rows)
    return m, method


def adjoint_sensitivities(model, contacts, excitation, solution, objective_gradient,
                          names=PARAMETERS, condensed=True,
                          relative_step=RELATIVE_STEP) -> Sensitivities:
    """dJ/dp_c of every contact c and parameter ``names`` at the converged ``solution``, from
    ∂J/∂ũ = ``objective_gradient`` (2H+1, n) by one adjoint solve (:func:`force_adjoint`) and the
    force differences of :func:`force_parameter_derivatives` (module docstring). J must not
    depend on p directly (∂J/∂p = 0, e.g. a level of the response)."""
    m, method = force_adjoint(model, contacts, excitation, solution, objective_gradient,
                              condensed)
    R = np.asarray(contacts.gap_map @ np.asarray(solution.displacement, dtype=float).T).T
    owner = contact_of_rows(contacts)
    used = owner >= 0
    derivative, step = {}, {}
    for name, (dforce, uses, h) in force_parameter_derivatives(
            contacts, R, solution.samples_per_period, solution.omega, names,
            relative_step).items():
        per_row = np.einsum("hr,hr->r", m, dforce)
        total = np.bincount(owner[used], weights=per_row[used], minlength=contacts.count)
        derivative[name] = np.where(uses, total, np.nan)
        step[name] = h
    return Sensitivities(derivative, step, m, method)
