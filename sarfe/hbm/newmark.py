r"""The Newmark march of the contact model: whole periods of M ü + D u̇ + K u + Gᵀ λ = f_e(t) from a
given state, the integrator behind :mod:`sarfe.hbm.time_integration` and the monodromy check of
:mod:`sarfe.hbm.stability.perturbation`.

The contact laws of :mod:`sarfe.hbm.laws` are evaluated pointwise in time, λ(r₊, ṙ₊)
(:class:`ContactLaws`, the same law functions as the AFT): the normal force of each law and, for
laws with a tangent element, its one-step return map (:func:`sarfe.hbm.laws.jenkins.step`) driven
by that normal force.

Scheme: Newmark average acceleration (trapezoidal rule; implicit, unconditionally stable, second
order, no numerical damping) with a fixed step h = T/N, N = ``steps_per_period``:

    u₊ = u + h v + h²/4 (a + a₊),   v₊ = v + h/2 (a + a₊),   M a₊ + D v₊ + K u₊ + Gᵀ λ₊ = f₊.

Eliminating a₊, v₊ gives  K_eff u₊ + Gᵀ λ(G u₊) = b,  K_eff = K + (2/h) D + (4/h²) M, factorized
once. With u_lin = K_eff⁻¹ b, B = K_eff⁻¹ Gᵀ and the contact compliance C = G B (n_rows, n_rows) the
step reduces to a small semismooth Newton iteration on the contact rows r = G u₊ only,

    R(r) = r + C λ(r, ṙ(r)) − G u_lin = 0,   J = I + C (∂λ/∂r + (2/h) ∂λ/∂ṙ),

with the Newmark velocity of the contact rows ṙ₊ = (2/h)(r₊ − r) − ṙ (so ∂ṙ₊/∂r₊ = 2/h),

followed by u₊ = u_lin − B λ. The friction history (slider positions) is updated by the exact
return map once r has converged. A step in which a stiff contact opens or closes (ω_c h >
SUBSTEP_RESOLUTION, ω_c its contact frequency) is redone in m sub-steps (:class:`_SubSteps`): the
rule conserves energy only while the law is linear, and an impact under-resolved in the step
gains energy (k_n = 10¹⁰ N/m, ω_c h ≈ 2: the orbit grows without bound or never settles).
:func:`march_periods` runs periods until the period-end state
(u, v/ω, sliders) repeats to a tolerance, optionally extrapolating the period-start states to the
periodic orbit (reduced-rank extrapolation).

For a linear system the scheme's periodic response is the exact one at the warped frequencies
ω'_k = (2/h) tan(kωh/2) (bilinear transform, :func:`warped_frequency`), so its amplitude error is
O((ωh)²); :func:`state_at_zero` is the scheme-consistent start state of a harmonic solution.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from sarfe.hbm import laws
from sarfe.hbm.laws import curvature

DENSE_LIMIT = 3000  # models up to this many DOFs use a dense propagator (reduced models)
#: ω_c h_s, the contact frequency × sub-step a stiff contact switches in (see :class:`_SubSteps`):
#: the trapezoidal rule's energy error of a closing or an opening is ≤ (ω_c h_s)²/4 of the impact's
#: kinetic energy (measured: 0.05/0.1/0.2 change the k_n = 10¹⁰ lumped rattle's orbit ≤ 0.2 %)
SUBSTEP_RESOLUTION = 0.1
MAX_SUBSTEPS = 256


def warped_frequency(frequency, omega, steps_per_period):
    """Bilinear-transform frequency (2/h) tan(ω_k h/2) [rad/s] seen by the trapezoidal rule with
    h = 2π/(ωN), N = ``steps_per_period`` (ω_k = ``frequency`` itself when N is None or ω_k = 0)."""
    if steps_per_period is None or frequency == 0:
        return frequency
    h = 2.0 * np.pi / (omega * steps_per_period)
    return 2.0 / h * np.tan(0.5 * frequency * h)


def state_at_zero(U, omega, steps_per_period):
    """u(0) [m] and the scheme-consistent v(0) [m/s] (n,) of harmonics U (2H+1, n) [m] at ω
    [rad/s]: u = u₀ + Σ u_kc, v = Σ ω'_k u_ks (ω'_k: :func:`warped_frequency`)."""
    H = (U.shape[0] - 1) // 2
    k = np.arange(1, H + 1)
    wk = np.array([warped_frequency(kk * omega, omega, steps_per_period) for kk in k])
    u0 = U[0] + U[1::2].sum(axis=0)
    v0 = (wk[:, None] * U[2::2]).sum(axis=0) if H else np.zeros_like(U[0])
    return u0, v0


class ContactLaws:
    """Contact forces λ(r, ṙ) and ∂λ/∂r, ∂λ/∂ṙ for all contacts at once (rows of G), given the
    slider history, law group by law group (:mod:`sarfe.hbm.laws`).

    ``forces`` evaluates the laws and keeps what ``jacobian`` needs (same r), so a converged
    Newton step costs one force evaluation. Sliders (n_s, 2): the contacts with a tangent element,
    in group order.
    """

    def __init__(self, contacts):
        self.n_rows = contacts.row_count
        self.n_c = contacts.count
        self.velocity = laws.velocity_dependent(contacts)
        self.groups = []
        first = 0
        for law, idx, p in laws.groups(contacts):
            nr = contacts.normal_row[idx]
            g = dict(law=law, idx=idx, p=p, gap=contacts.gap[idx], has_normal=nr >= 0,
                     normal_safe=np.maximum(nr, 0))
            g["normal_rows"] = nr[g["has_normal"]]
            g["kappa"] = curvature.curvatures(p)   # a curved partner: w − ½ Σ κ q², :mod:`curvature`
            if g["kappa"] is not None:
                g["all_t"] = contacts.tangent_rows[idx]
            sel = np.flatnonzero(contacts.tangent_rows[idx, 0] >= 0) if law.tangent is not None \
                else np.zeros(0, int)
            g["tangent"] = sel.size > 0        # the element acts on the contacts with tangent rows
            if g["tangent"]:
                t_rows = contacts.tangent_rows[idx[sel]]
                mask = t_rows >= 0
                g.update(t_sel=sel, p_t={k: v[sel] for k, v in p.items()}, t_mask=mask,
                         t_safe=np.where(mask, t_rows, 0), t_used=t_rows[mask],
                         sliders=slice(first, first + sel.size))
                first += sel.size
                pair = mask[:, :, None] & mask[:, None, :]
                g.update(pair=pair,
                         pair_rows=np.broadcast_to(g["t_safe"][:, :, None], pair.shape)[pair],
                         pair_cols=np.broadcast_to(g["t_safe"][:, None, :], pair.shape)[pair])
                coupled = mask & g["has_normal"][sel][:, None]
                g.update(coupled=coupled, coupled_rows=g["t_safe"][coupled],
                         coupled_cols=np.broadcast_to(g["normal_safe"][sel][:, None],
                                                      coupled.shape)[coupled])
            self.groups.append(g)
        self.slider_count = first

    def length_floor(self, gap):
        """Round-off floor of the contact Newton [m]: 1e-15 × the largest gap or slip length."""
        lengths = [np.abs(gap).max(initial=0.0)]
        for g in self.groups:
            if g["tangent"]:
                lengths.append(g["law"].tangent.slip_length(g["p_t"]).max(initial=0.0))
        return 1e-15 * max(max(lengths), 1e-9)

    def forces(self, r, rdot, slider_previous):
        """λ (n_rows,), slider (n_s, 2), state (n_c,) int8 at contact displacements r (n_rows,) and
        velocities ṙ (n_rows,) (None: all laws rate independent)."""
        lam = np.zeros(self.n_rows)
        state = np.zeros(self.n_c, dtype=np.int8)
        slider = slider_previous.copy() if self.slider_count else slider_previous
        self._last = []
        for g in self.groups:
            has = g["has_normal"]
            w = np.where(has, r[g["normal_safe"]], g["gap"])
            wdot = np.where(has, rdot[g["normal_safe"]], 0.0) if rdot is not None else None
            if g["kappa"] is not None:
                q_all = np.where(g["all_t"] >= 0, r[np.maximum(g["all_t"], 0)], 0.0)
                w = curvature.effective_normal(g["kappa"], w, q_all)
            out = g["law"].normal(g["p"], g["gap"], w, wdot)
            lam[g["normal_rows"]] = out.force[has]
            state[g["idx"]] = out.closed
            keep = {"stiffness": np.where(has, out.stiffness, 0.0),
                    "damping": None if out.damping is None else np.where(has, out.damping, 0.0)}
            if g["tangent"]:
                q = r[g["t_safe"]] * g["t_mask"]
                force_t, new, fstate, d_tq, d_tn = g["law"].tangent.step(
                    g["p_t"], q, out.force[g["t_sel"]], slider_previous[g["sliders"]])
                lam[g["t_used"]] = force_t[g["t_mask"]]
                state[g["idx"][g["t_sel"]]] = fstate
                slider[g["sliders"]] = new
                keep.update(d_tq=d_tq, d_tn=d_tn)
            if g["kappa"] is not None:
                geometric = curvature.coupling(g["kappa"], q_all, out.force, keep["stiffness"])[0]
                on = g["all_t"] >= 0
                np.add.at(lam, g["all_t"][on], geometric[on])
                keep.update(q=q_all, force=out.force)
            self._last.append(keep)
        return lam, slider, state

    def jacobian(self, rate_factor=0.0):
        """∂λ/∂r + rate_factor ∂λ/∂ṙ (n_rows, n_rows) at the r of the last :meth:`forces` call
        (semismooth); rate_factor = ∂ṙ/∂r = 2/h in the Newmark step."""
        jac = np.zeros((self.n_rows, self.n_rows))
        for g, keep in zip(self.groups, self._last):
            has = g["has_normal"]
            stiffness = keep["stiffness"]
            if keep["damping"] is not None:
                stiffness = stiffness + rate_factor * keep["damping"]
            if g["kappa"] is not None:           # the coupled (w, q₁, q₂) block of each contact
                d_tq, d_tn = np.zeros((has.size, 2, 2)), np.zeros((has.size, 2))
                if g["tangent"]:
                    d_tq[g["t_sel"]], d_tn[g["t_sel"]] = keep["d_tq"], keep["d_tn"]
                local = curvature.local_jacobian(g["kappa"], keep["q"], keep["force"], stiffness,
                                                 d_tq, d_tn)
                rows = np.column_stack([np.where(has, g["normal_safe"], -1), g["all_t"]])
                valid = (rows[:, :, None] >= 0) & (rows[:, None, :] >= 0)
                np.add.at(jac, (np.broadcast_to(rows[:, :, None], valid.shape)[valid],
                                np.broadcast_to(rows[:, None, :], valid.shape)[valid]), local[valid])
                continue
            jac[g["normal_rows"], g["normal_rows"]] = stiffness[has]
            if g["tangent"]:
                jac[g["pair_rows"], g["pair_cols"]] += keep["d_tq"][g["pair"]]
                if g["coupled_rows"].size:   # slip limit follows the normal force
                    d_tn = keep["d_tn"] * stiffness[g["t_sel"], None]
                    jac[g["coupled_rows"], g["coupled_cols"]] += d_tn[g["coupled"]]
        return jac


def initial_sliders(law, r0, initial_force):
    """Slider positions w (n_s, 2) [m] of the :class:`ContactLaws` ``law`` at contact displacements
    r0 (n_rows,) [m]: w = q − λ_t/k_t from a given contact force ``initial_force`` (n_rows,) [N],
    or w = q (unloaded springs) when it is None."""
    slider = np.zeros((law.slider_count, 2))
    for g in law.groups:
        if not g["tangent"]:
            continue
        q = np.where(g["t_mask"], r0[g["t_safe"]], 0.0)
        force = None if initial_force is None else np.where(g["t_mask"],
                                                            initial_force[g["t_safe"]], 0.0)
        if force is not None and g["kappa"] is not None:   # less the normal force's −κ q λ_n
            sel = g["t_sel"]
            normal = np.where(g["has_normal"][sel], initial_force[g["normal_safe"][sel]], 0.0)
            force = force + g["kappa"][sel] * q * normal[:, None]
        slider[g["sliders"]] = g["law"].tangent.initial_slider(g["p_t"], q, force)
    return slider


class _Propagator:
    """Linear part of one Newmark step: u_lin = K_eff⁻¹ (f₊ + M(c₀u + c₁v + a) + D(c₂u + v))."""

    def __init__(self, model, h, gap_map, forcing):
        M, D, K = model.mass, model.damping, model.stiffness
        c0, c1, c2 = 4.0 / h**2, 4.0 / h, 2.0 / h
        n = M.shape[0]
        self.dense = n <= DENSE_LIMIT
        if self.dense:
            Md, Dd, Kd = (np.asarray(x.toarray() if sp.issparse(x) else x, dtype=float) for x in (M, D, K))
            factor = la.cho_factor(Kd + c2 * Dd + c0 * Md)
            solve = lambda b: la.cho_solve(factor, b)  # noqa: E731
            self.P = solve(np.hstack([c0 * Md + c2 * Dd, c1 * Md + Dd, Md]))  # (n, 3n)
        else:
            Ms, Ds, Ks = (sp.csc_matrix(x) for x in (M, D, K))
            lu = spla.splu((Ks + c2 * Ds + c0 * Ms).tocsc())
            solve = lu.solve
            self.M, self.D, self.lu, self.c = Ms, Ds, lu, (c0, c1, c2)
        self.solve, self.h = solve, h
        # K_eff⁻¹ f_j (N, n) at the period's samples; None for a sub-step propagator (f given)
        self.g = None if forcing is None else solve(forcing.T).T if forcing.shape[0] else forcing
        rows_t = gap_map.T.toarray() if sp.issparse(gap_map) else gap_map.T
        self.B = solve(rows_t) if gap_map.shape[0] else np.zeros((n, 0))
        self.B = self.B.reshape(n, -1)
        self.C = np.asarray(gap_map @ self.B)                             # contact compliance

    def linear(self, u, v, a, j, force=None):
        """u_lin at the end of the step to sample j (or with the load ``force`` (n,) [N])."""
        load = self.g[j] if force is None else self.solve(force)
        if self.dense:
            return self.P @ np.concatenate((u, v, a)) + load
        c0, c1, c2 = self.c
        return self.lu.solve(self.M @ (c0 * u + c1 * v + a) + self.D @ (c2 * u + v)) + load


class _SubSteps:
    r"""Steps in which a stiff contact opens or closes, redone in m equal sub-steps h_s = h/m (the
    trapezoidal rule conserves energy only while the law is linear).

    A contact that closes at a fraction α of a step ends it with penetration p ≈ (1 − α) ṙ h; the
    rule's work Δr·λ̄ differs from the stored energy ½ k p² by α(1 − α)(ω_c h)² of the impact's
    kinetic energy (ω_c² = k/m, m the contact's mass). The errors of closing and opening cancel
    only for an isolated free impact (the rule is time-symmetric); with the springs, the load and
    a second body in the impact they do not: k_n = 10¹⁰ N/m on the lumped rattle, N = 2048 at
    71.5 Hz (ω_c h = 1.8), the contact's cyclic work was −36 % of the input and the orbit never
    settled; a driven 1-DOF impact oscillator grew to 10³⁵ m at N = 256.

    The contact's ρ = ‖C ∂λ/∂r‖∞ ≈ (ω_c h/2)² (C = G K_eff⁻¹ Gᵀ ≈ (h²/4) G M⁻¹ Gᵀ) measures ω_c h
    for any law. A step in which a contact opens or closes (state 0 ↔ not 0; stick ↔ slip keeps
    the step: friction dissipates) with 2√ρ > SUBSTEP_RESOLUTION (the larger ρ of its start and
    end) is redone in m = 2^⌈log₂(2√ρ / SUBSTEP_RESOLUTION)⌉ ≤ MAX_SUBSTEPS sub-steps, the load
    f_e(t) trigonometrically interpolated between the samples. Contacts the step resolves
    (ω_c h ≤ SUBSTEP_RESOLUTION at their switches) give the results of the plain rule.
    """

    def __init__(self, model, h, gap_map, forcing):
        self.model, self.h, self.G = model, h, gap_map
        self.N = forcing.shape[0]
        spectrum = np.fft.rfft(forcing, axis=0) / self.N            # f_j = Re Σ_k w_k c_k e^{ikθ_j}
        size = np.abs(spectrum).max(axis=1)
        self.k = np.flatnonzero(size > 1e-14 * max(size.max(initial=0.0), 1e-300))
        weight = np.where((self.k == 0) | (2 * self.k == self.N), 1.0, 2.0)
        self.c = weight[:, None] * spectrum[self.k]
        self.forcing, self.props = forcing, {}

    def load(self, position):
        """f_e at sample position j + s (n,) [N] (exact for a load of fewer than N/2 harmonics)."""
        phase = np.exp(2j * np.pi * self.k * position / self.N)
        return (phase @ self.c).real

    def count(self, law, C, state, state_new, r, rdot, slider):
        """Number of sub-steps m of a step from contact state ``state`` to ``state_new`` (1: keep);
        called after the step's contact solve (the laws' last evaluation is its end), with the
        start's contact displacement r, velocity ṙ (None: rate-independent laws) and sliders."""
        if np.array_equal(state == 0, state_new == 0):     # no contact opened or closed
            return 1

        def rho():         # ‖C ∂λ/∂r‖∞ at the laws' last evaluation
            return np.abs(C @ law.jacobian(2.0 / self.h)).sum(axis=1).max(initial=0.0)

        at_end = rho()
        law.forces(r, rdot, slider)                          # the start (a contact that opens)
        ratio = 2.0 * np.sqrt(max(at_end, rho())) / SUBSTEP_RESOLUTION
        if ratio <= 1.0:
            return 1
        return int(min(2 ** np.ceil(np.log2(ratio)), MAX_SUBSTEPS))

    def march(self, contact, law, j, m, u, v, a, lam, slider, r):
        """The step j → j + 1 in m sub-steps from (u, v, a, λ, slider, r); returns the end state
        (u, v, a, λ, slider, state, r), its work (input, damping, contact rows) and the most
        contact Newton iterations of a sub-step."""
        if m not in self.props:
            self.props[m] = _Propagator(self.model, self.h / m, self.G, None)
        prop, hs, G, D = self.props[m], self.h / m, self.G, self.model.damping
        f_prev = self.forcing[j]
        work_input = work_damping = 0.0
        work_contact = np.zeros(r.size)
        worst = 0
        for i in range(1, m + 1):
            f = self.forcing[(j + 1) % self.N] if i == m else self.load(j + i / m)
            u_lin = prop.linear(u, v, a, None, f)
            r_lin = G @ u_lin
            lam_new, slider, state, r_new, iterations = contact(
                r_lin, slider, r_lin - prop.C @ lam, r, G @ v if law.velocity else None, prop)
            worst = max(worst, iterations)
            u_new = u_lin - prop.B @ lam_new
            du = u_new - u
            work_input += du @ (0.5 * (f_prev + f))
            work_damping += du @ (D @ du) / hs
            work_contact += (r_new - r) * 0.5 * (lam + lam_new)
            a = 4.0 / hs**2 * (du - hs * v) - a
            v = 2.0 / hs * du - v
            u, lam, r, f_prev = u_new, lam_new, r_new, f
        return u, v, a, lam, slider, state, r, (work_input, work_damping, work_contact), worst


def _extrapolation_weights(steps):
    """Reduced-rank extrapolation: γ minimizing ‖Σ γ_i Δ_i‖ with Σ γ_i = 1 (None if degenerate).

    For a period map x₊ = A x + b the fixed point is Σ γ_i x_{i+1} once the Δ_i span the transient.
    """
    gram = steps @ steps.T
    scale = np.trace(gram)
    if not np.isfinite(scale) or scale <= 0:
        return None
    y = np.linalg.lstsq(gram / scale + 1e-13 * np.eye(len(gram)), np.ones(len(gram)), rcond=None)[0]
    if abs(y.sum()) < 1e-300:
        return None
    return y / y.sum()


def march_periods(model, contacts, forcing, omega, N, u, v, slider, max_periods, steady_tolerance,
                  accelerate, progress, period_offset, section_dofs=None):
    """Integrate whole periods from (u, v, slider) at t = 0 until periodic; returns a dict.

    forcing f_e(t_j) (N, n_dof) [N] at the N samples of one period 2π/ω; u [m], v [m/s] (n_dof,),
    slider (n_s, 2) [m] (:func:`initial_sliders`); at most ``max_periods`` periods, ended when the
    period-end state (u, v/ω, sliders) repeats to ``steady_tolerance`` relative to the amplitude;
    ``progress``: callable(period_offset + periods done, None) or None; ``section_dofs``: DOFs of
    the Poincaré section (all by default).

    With ``accelerate``, every few periods the period-start states are extrapolated to the fixed
    point of the period map (reduced-rank extrapolation); a jump that does not lower the
    periodicity error is undone, and the next try waits longer (off after 4 failures).

    Returns a dict of the last period: u, v (N, n_dof), r, lam (N, n_rows), state (N, n_c) int8,
    periods, steady, error (periodicity), input_work, damping_work [J], contact_work (n_c,) [J],
    iterations (most contact Newton iterations of a step), final = (u, v, slider) at its end,
    section (P + 1, 2 n_section).
    """
    n = u.size
    h = 2.0 * np.pi / (omega * N)
    dense = n <= DENSE_LIMIT
    if contacts is None:
        G = np.zeros((0, n))
    else:  # dense rows for small (reduced) models, sparse matvecs for big ones
        G = contacts.gap_map.toarray() if dense else sp.csr_matrix(contacts.gap_map)
    law = ContactLaws(contacts) if contacts is not None and contacts.count else None
    n_rows, n_c = G.shape[0], (contacts.count if contacts is not None else 0)
    prop = _Propagator(model, h, G, forcing)
    M, D, K = model.mass, model.damping, model.stiffness
    identity = np.eye(n_rows)
    if law is not None:  # round-off floor of the contact Newton [m]
        length_floor = law.length_floor(contacts.gap)
    # Newmark: ṙ₊ = (2/h)(r₊ − r) − ṙ, ∂ṙ₊/∂r₊ = 2/h
    fine = _SubSteps(model, h, G, forcing) if law is not None else None

    def contact(r_lin, slider_prev, r_guess, r_start, rdot_start, step_prop=prop):
        """Solve r + C λ(r, ṙ(r)) = r_lin (semismooth Newton, C and ṙ of the step ``step_prop``);
        returns λ, slider, state, r, iterations."""
        r = r_guess
        rate = 2.0 / step_prop.h
        tolerance = 1e-12 * np.abs(r_lin).max() + length_floor
        for it in range(1, 60):
            rdot = rate * (r - r_start) - rdot_start if law.velocity else None
            lam, new_slider, state = law.forces(r, rdot, slider_prev)
            residual = r + step_prop.C @ lam - r_lin
            if np.abs(residual).max() <= tolerance:
                break
            step = np.linalg.solve(identity + step_prop.C @ law.jacobian(rate), residual)
            r = r - (0.5 * step if it > 30 else step)  # damp if cycling between active sets
        return lam, new_slider, state, r, it

    Md = (M.toarray() if sp.issparse(M) else np.asarray(M)) if dense else None

    def restart(u, v, slider):
        """Contact forces and the consistent acceleration M a = f − K u − D v − Gᵀλ at t = 0."""
        if law is not None:
            lam, slider, state = law.forces(G @ u, G @ v if law.velocity else None, slider)
        else:
            lam, state = np.zeros(0), np.zeros(0, dtype=np.int8)
        rhs = forcing[0] - K @ u - D @ v - G.T @ lam
        a = np.linalg.solve(Md, rhs) if dense else spla.spsolve(sp.csc_matrix(M), rhs)
        return a, slider, lam, state

    def pack(u, v, slider):
        return np.concatenate((u, v / omega, slider.ravel()))

    def unpack(x):
        return x[:n], omega * x[n:2 * n], x[2 * n:].reshape(-1, 2)

    a, slider, lam, state = restart(u, v, slider)
    u_samples = np.empty((N, n))
    v_samples = np.empty((N, n))
    r_samples = np.empty((N, n_rows))
    lam_samples = np.empty((N, n_rows))
    state_samples = np.empty((N, n_c), dtype=np.int8)
    error, steady, periods, worst_iterations = np.inf, False, 0, 0
    window = min(2 * n + slider.size, 12)
    history, jumped, failures, wait = [], None, 0, 0
    section_dofs = np.arange(n) if section_dofs is None else section_dofs
    section, sub_work = [], {}
    while periods < max_periods:
        start = pack(u, v, slider)
        section.append(np.concatenate((u[section_dofs], v[section_dofs] / omega)))
        r_prev = G @ u
        sub_work = {}     # step j → its work (input, damping, contact rows) summed over sub-steps
        for j in range(N):
            u_samples[j], v_samples[j] = u, v
            r_samples[j], lam_samples[j] = r_prev, lam
            if n_c:
                state_samples[j] = state
            u_lin = prop.linear(u, v, a, (j + 1) % N)
            if law is not None:
                r_lin = G @ u_lin
                guess = r_lin - prop.C @ lam  # predictor: last step's contact force
                rdot = G @ v if law.velocity else None
                lam_new, slider_new, state_new, r_new, iterations = contact(
                    r_lin, slider, guess, r_prev, rdot)
                worst_iterations = max(worst_iterations, iterations)
                m = fine.count(law, prop.C, state, state_new, r_prev, rdot, slider)
                if m > 1:   # a stiff contact switched within the step: redo it in m sub-steps
                    u, v, a, lam, slider, state, r_prev, sub_work[j], iterations = fine.march(
                        contact, law, j, m, u, v, a, lam, slider, r_prev)
                    worst_iterations = max(worst_iterations, iterations)
                    continue
                slider, state = slider_new, state_new
                u_new = u_lin - prop.B @ lam_new
            else:
                lam_new, r_new, u_new = lam, r_prev, u_lin
            du = u_new - u
            v_new = 2.0 / h * du - v
            a = 4.0 / h**2 * (du - h * v) - a
            u, v, lam, r_prev = u_new, v_new, lam_new, r_new
        periods += 1
        end = pack(u, v, slider)
        amplitude = max(np.abs(u_samples).max(), np.abs(v_samples).max() / omega, 1e-300)
        error = np.abs(end - start).max() / amplitude
        if progress is not None:
            progress(period_offset + periods, None)
        if error <= steady_tolerance:
            steady = True
            break
        if not accelerate or periods >= max_periods:
            continue
        if jumped is not None:  # judge the last extrapolation by the period that followed it
            before, error_before = jumped
            jumped = None
            if error > error_before:  # it made things worse: undo, wait longer before the next try
                failures += 1
                accelerate = failures < 4
                wait = periods + window * 2**failures
                u, v, slider = unpack(before)
                a, slider, lam, state = restart(u, v, slider)
                continue
        if periods < wait:
            continue
        history.append(start)
        if len(history) > window:
            states = np.array(history[1:] + [end])              # x_1 … x_m
            steps = np.diff(np.array(history + [end]), axis=0)  # Δ_i = x_{i+1} − x_i
            shrinking = np.abs(steps[-1]).max() < 0.5 * np.abs(steps[0]).max()
            # extrapolate only a decaying transient: RRE would also find unstable orbits
            weight = _extrapolation_weights(steps) if shrinking else None
            if weight is not None:
                jumped = (end, error)
                u, v, slider = unpack(weight @ states)
                a, slider, lam, state = restart(u, v, slider)
            history = []
    # work over the last period by the discrete identity of the trapezoidal rule (exact balance):
    # Δu·f̄, Δuᵀ D Δu / h, Δr·λ̄ per step
    # (a sub-stepped step: the same sums over its sub-steps)
    du = np.diff(np.vstack((u_samples, u)), axis=0)
    input_step = np.sum(du * 0.5 * (forcing + np.roll(forcing, -1, axis=0)), axis=1)
    damping_step = np.sum(du * (D @ du.T).T, axis=1) / h
    contact_step = (np.diff(np.vstack((r_samples, r_prev)), axis=0)
                    * 0.5 * (lam_samples + np.vstack((lam_samples[1:], lam))))
    for j, (step_input, step_damping, step_contact) in sub_work.items():
        input_step[j], damping_step[j], contact_step[j] = step_input, step_damping, step_contact
    input_work, damping_work = float(input_step.sum()), float(damping_step.sum())
    contact_work = contact_step.sum(axis=0)
    per_contact = np.zeros(n_c)
    if n_c:
        owner = np.full(n_rows, -1)
        owner[contacts.normal_row[contacts.normal_row >= 0]] = np.flatnonzero(contacts.normal_row >= 0)
        for col in range(2):
            rows = contacts.tangent_rows[:, col]
            owner[rows[rows >= 0]] = np.flatnonzero(rows >= 0)
        np.add.at(per_contact, owner[owner >= 0], contact_work[owner >= 0])
    return dict(
        u=u_samples, v=v_samples, r=r_samples, lam=lam_samples, state=state_samples,
        periods=periods, steady=steady, error=error, input_work=input_work,
        damping_work=damping_work, contact_work=per_contact, iterations=worst_iterations,
        substeps=len(sub_work), final=(u, v, slider),
        section=np.array(section + [np.concatenate((u[section_dofs], v[section_dofs] / omega))]),
    )
