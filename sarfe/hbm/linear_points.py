r"""Linear points: where every contact keeps the state it is linearized in at u = 0 (open, closed,
stuck) over the whole period, the harmonic-balance solution is the response of the linearized model
— one modal sum, no Newton, no Hill.

The linearized model (each law's linearization at u = 0, :func:`sarfe.hbm.solve.linearized_rows`:
springs k_s, dashpots c and preloads p on the rows of G of the contacts closed at u = 0, stuck
tangents as springs k_t) answers at the contact rows, per loaded order k (Woodbury on the model's
compliance, :func:`sarfe.hbm.pruning.contact_row_responses`)

    (I + C_k diag(k_s + i kω c)) r̂_k = G Z_k⁻¹ f̂_k,    (I + C_0 diag(k_s)) r̂_0 = G K⁻¹ f̂_0 − C_0 p,
    λ̂_k = (k_s + i kω c) r̂_k (+ p for k = 0),        û_k = Z_k⁻¹ (f̂_k − Gᵀ λ̂_k),

with C_k = G Z_k⁻¹ Gᵀ and Z_k⁻¹ = K⁻¹ + V diag(q_k) Vᵀ from the model's modal basis
(:mod:`sarfe.hbm.modal`; other models: the direct solves of :func:`sarfe.hbm.pruning.
linear_responses`). Orders without excitation are zero. The point is accepted
(:func:`linear_point`) only when the AFT of the true laws at the N samples gives every contact its
linearized state at every sample (0 open, 1 closed or stuck; :func:`linear_states_hold`) and the
full residual ‖S ũ + Gᵀ λ̃(ũ) − f̃_e‖ / ‖f̃_e‖ is within ``full_tolerance`` — ũ then solves the
harmonic-balance equations R(ũ) = 0 themselves, to round-off: the laws are linear on the states
they stay in (a friction contact stuck the whole period with 0 in its stick set keeps λ_t = k_t q:
:mod:`sarfe.hbm.laws.jenkins`, its gauge). Such an orbit is that of a damped linear system: stable
(all modal damping > 0), reported without a Hill computation.

Screening (:func:`linear_with_margin`): the same state test on r̃_0 + a (r̃ − r̃_0), the dynamic part
amplified by a = 1/(1 − m) (m the case's ``prune_margin``, 0.5 by default: a rattle gap is used at
most half, a stuck contact's friction reserve at least half) — where a sweep may take linear points
instead of following the branch (:mod:`sarfe.pipeline.solve.by_need`).
"""
from __future__ import annotations

import numpy as np

from sarfe.hbm import laws
from sarfe.hbm.aft import contact_forces
from sarfe.hbm.dynamic_stiffness import from_complex, to_complex
from sarfe.hbm.modal import cached_modal_basis, real_product
from sarfe.hbm.pruning import linear_responses, modal_row_responses
from sarfe.hbm.residual import full_residual
from sarfe.hbm.solution import HarmonicSolution, SolverOptions
from sarfe.hbm.solve import kept_residual_norm, linearized_rows, make_problem

LINEAR_REASON = "linear point: every contact stays open, closed or stuck (exact linear solution)"
LINEAR_NOTE = "linear point: the orbit of the damped linearized model (no Hill computation)"


def linearized_states(contacts) -> np.ndarray:
    """(n_c,) int8: the AFT state each contact has on its linearization at u = 0 — 1 (closed, or
    stuck under a normal load) for the contacts the laws linearize as closed, else 0 (open)."""
    return laws.linearization(contacts)[0].closed.astype(np.int8)


def linear_states_hold(contacts, contact_displacement, samples_per_period, omega,
                       amplification=1.0) -> bool:
    """True when every contact is in its linearized state (:func:`linearized_states`) at all
    ``samples_per_period`` samples of r̃_0 + a (r̃ − r̃_0) (r̃ (2H+1, n_rows) [m], a =
    ``amplification`` ≥ 1: the dynamic part amplified, a margin), by the laws' own AFT."""
    R = np.array(contact_displacement, dtype=float)
    R[1:] *= float(amplification)
    forces = contact_forces(contacts, R, int(samples_per_period), jacobian=False, omega=omega)
    state = np.asarray(forces.state)
    return bool(np.all(state == linearized_states(contacts)[None, :]))


def linear_with_margin(contacts, contact_displacement, samples_per_period, omega,
                       margin=0.5) -> bool:
    """:func:`linear_states_hold` with a = 1/(1 − margin) (module docstring)."""
    return linear_states_hold(contacts, contact_displacement, samples_per_period, omega,
                              1.0 / (1.0 - float(margin)))


def screen_linear(model, contacts, excitation, omegas, samples_per_period=64,
                  margin=0.5) -> np.ndarray:
    """(n_ω,) bool: at which ω [rad/s] the linearized response is linear with the margin
    (:func:`linear_with_margin`) — the contact rows only, vectorized over ω
    (:func:`linear_row_responses`)."""
    omegas = np.atleast_1d(np.asarray(omegas, dtype=float))
    R = linear_row_responses(model, contacts, excitation, omegas)
    return np.array([np.all(np.isfinite(r)) and linear_with_margin(contacts, r, samples_per_period,
                                                                   w, margin)
                     for r, w in zip(R, omegas)], dtype=bool)


def loaded_order_count(excitation) -> int:
    """h: the highest harmonic order with excitation (0: a static load only)."""
    F = np.asarray(excitation, dtype=float)
    loaded = np.flatnonzero(np.any(F[1:] != 0, axis=1))
    return int(loaded[-1] + 2) // 2 if loaded.size else 0


def linear_row_responses(model, contacts, excitation, omegas) -> np.ndarray:
    """r̃ = G ũ (n_ω, 2h+1, n_rows) [m] of the linearized model at the loaded orders 0 … h
    (:func:`loaded_order_count`): the modal Woodbury form where the model has a modal basis, else
    the direct solves (module docstring)."""
    F = np.asarray(excitation, dtype=float)
    F = F[:2 * loaded_order_count(F) + 1]
    omegas = np.atleast_1d(np.asarray(omegas, dtype=float))
    basis = modal_basis_of(model)
    G = contacts.gap_map
    if basis is None:
        return np.stack([np.asarray(G @ U.T).T
                         for U in linear_responses(model, contacts, F, omegas)])
    R, bad = modal_row_responses(basis, contacts, F, omegas)
    if np.any(bad):
        R[bad] = np.stack([np.asarray(G @ U.T).T
                           for U in linear_responses(model, contacts, F, omegas[bad])])
    return R


def modal_basis_of(model):
    """The model's cached modal basis (computed now if it was seen once), or None."""
    return cached_modal_basis(model) or cached_modal_basis(model)


def linear_displacements(model, contacts, excitation, omegas) -> np.ndarray:
    """ũ (n_ω, 2H+1, n) [m] of the linearized model at each ω [rad/s] (module docstring; orders
    above the loaded ones zero). Modal models: from the row responses, û_k = K⁻¹ g_k +
    V (q_k ⊙ Vᵀ g_k), g_k = f̂_k − Gᵀ λ̂_k; other models: direct solves."""
    F = np.asarray(excitation, dtype=float)
    H = (F.shape[0] - 1) // 2
    h = loaded_order_count(F)
    omegas = np.atleast_1d(np.asarray(omegas, dtype=float))
    basis = modal_basis_of(model)
    out = np.zeros((omegas.size, 2 * H + 1, model.dof_count))
    if basis is None:
        for i, U in enumerate(linear_responses(model, contacts, F[:2 * h + 1], omegas)):
            out[i, :2 * h + 1] = U
        return out
    R = linear_row_responses(model, contacts, F, omegas)         # (n_ω, 2h+1, n_rows)
    springs, dashpots, preload = linearized_rows(contacts)
    G = contacts.gap_map
    n, n_rows = model.dof_count, G.shape[0]
    kw = np.arange(h + 1)[:, None] * omegas[None, :]            # kω (h+1, n_ω)
    L = (springs + 1j * kw[..., None] * dashpots) * to_complex(np.moveaxis(R, 1, 0))
    L[0] += preload                                              # λ̂_k (h+1, n_ω, n_rows)
    g = to_complex(F[:2 * h + 1])[:, None, :] - np.asarray(
        G.T @ L.reshape(-1, n_rows).T).T.reshape(L.shape[:2] + (n,))   # f̂_k − Gᵀλ̂_k
    flat = g.reshape(-1, n)
    q = basis.dynamic_receptance(kw.ravel(), 1.0)                # q_kj at kω (…, n_modes)
    U = (basis.static_solve(flat.T).T
         + real_product(q * real_product(flat, basis.modes), basis.modes.T)).reshape(g.shape)
    out[:, :2 * h + 1] = np.moveaxis(from_complex(U), 1, 0)
    return out


def linear_point(model, contacts, excitation, omega, harmonics, samples_per_period,
                 displacement=None, options=None) -> HarmonicSolution | None:
    """The HarmonicSolution at ω [rad/s] when the linearized response is a solution (module
    docstring: every contact in its linearized state at every sample, full residual within
    ``options.full_tolerance``), else None. ``displacement``: ũ (2H+1, n) of the linearized model
    when already computed (:func:`linear_displacements`)."""
    options = options or SolverOptions()
    problem = make_problem(model, contacts, excitation, harmonics, samples_per_period, options)
    U = (linear_displacements(model, contacts, excitation, [omega])[0] if displacement is None
         else np.asarray(displacement, dtype=float))
    if not np.all(np.isfinite(U)):
        return None
    with np.errstate(all="ignore"):
        ev = full_residual(problem, U.ravel(), float(omega), None, jacobian=False)
    state = np.asarray(ev.forces.state)
    residual = kept_residual_norm(problem, ev)
    if not (np.all(state == linearized_states(contacts)[None, :])
            and np.isfinite(residual) and residual <= options.full_tolerance):
        return None
    basis = modal_basis_of(model)
    stable = None if basis is None else bool(np.all(basis.damping > 0))
    G = contacts.gap_map
    return HarmonicSolution(
        omega=float(omega), harmonics=int(harmonics), samples_per_period=int(samples_per_period),
        displacement=U, contact_displacement=np.asarray(G @ U.T).T,
        contact_force=ev.forces.force, contact_force_time=ev.forces.force_time,
        contact_state=ev.forces.state, converged=True, reason=LINEAR_REASON, iterations=0,
        residual_norm=residual, friction_passes=int(ev.forces.friction_passes),
        stable=stable if options.stability else None,
        stability_note=LINEAR_NOTE if options.stability else "", dropped_content=0.0,
        method="linear")


__all__ = ["LINEAR_REASON", "LINEAR_NOTE", "linearized_states", "linear_states_hold",
           "linear_with_margin", "screen_linear", "loaded_order_count", "linear_row_responses",
           "modal_basis_of", "linear_displacements", "linear_point"]
