r"""Time integration of the contact model to its periodic steady state (the HBM's independent check).

Equation (the same model as the harmonic balance, see :mod:`sarfe.hbm.contacts`)

    M ü + D u̇ + K u + Gᵀ λ(G u, history) = f_e(t),
    f_e(t) = F0 + Σ_k F_kc cos kωt + F_ks sin kωt        (F = ``excitation``, (2H+1, n_dof) [N])

with the contact laws of :mod:`sarfe.hbm.laws` evaluated pointwise in time, λ(r₊, ṙ₊) (the same
law functions as the AFT): the normal force of each law and, for laws with a tangent element, its
one-step return map (:func:`sarfe.hbm.laws.jenkins.step`) driven by that normal force.

Scheme: Newmark average acceleration (trapezoidal rule; implicit, unconditionally stable, second
order, no numerical damping) with a fixed step h = T/N, N = ``steps_per_period``:

    u₊ = u + h v + h²/4 (a + a₊),   v₊ = v + h/2 (a + a₊),   M a₊ + D v₊ + K u₊ + Gᵀ λ₊ = f₊.

Eliminating a₊, v₊ gives  K_eff u₊ + Gᵀ λ(G u₊) = b,  K_eff = K + (2/h) D + (4/h²) M, factorized
once. With u_lin = K_eff⁻¹ b, B = K_eff⁻¹ Gᵀ and the contact compliance C = G B (n_rows, n_rows) the
step reduces to a small semismooth Newton iteration on the contact rows r = G u₊ only,

    R(r) = r + C λ(r, ṙ(r)) − G u_lin = 0,   J = I + C (∂λ/∂r + (2/h) ∂λ/∂ṙ),

with the Newmark velocity of the contact rows ṙ₊ = (2/h)(r₊ − r) − ṙ (so ∂ṙ₊/∂r₊ = 2/h),

followed by u₊ = u_lin − B λ. The friction history (slider positions) is updated by the exact
return map once r has converged. Periods are run until the period-end state (u, v/ω, sliders)
repeats to ``steady_tolerance`` (relative to the response amplitude); the last period is Fourier
analysed with the convention of :mod:`sarfe.hbm.harmonics`.

For a linear system the scheme's periodic response is the exact one at the warped frequencies
ω'_k = (2/h) tan(kωh/2) (bilinear transform), so its amplitude error is O((ωh)²). The run starts
from that discrete linear periodic solution (or from a given HBM solution), which removes the
transient of the linear part.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from sarfe.hbm import laws
from sarfe.hbm.harmonics import harmonic_coefficients, time_samples

__all__ = ["TimeResponse", "integrate_time", "integrate_transient", "linear_harmonic_response",
           "period_work", "section_spread"]

DENSE_LIMIT = 3000  # models up to this many DOFs use a dense propagator (reduced models)


@dataclass(frozen=True)
class TimeResponse:
    """Periodic steady state found by time integration, sampled over its last period.

    Samples are at t_j = j T / N, j = 0 … N−1 (phase θ_j = ω t_j = 2πj/N, aligned with the
    excitation and with the AFT samples of :class:`HarmonicSolution`). SI units.

    omega [rad/s], harmonics H, steps_per_period N
    time (N,) [s]                          t_j within the period
    output_dofs (n_out,) int               DOFs kept in ``displacement`` / ``velocity``
    displacement (N, n_out) [m], velocity (N, n_out) [m/s]
    displacement_harmonics (2H+1, n_dof) [m]   all DOFs (Richardson-extrapolated if requested)
    contact_displacement (N, n_rows) [m]   r = G u
    contact_force (N, n_rows) [N]          λ
    contact_force_harmonics (2H+1, n_rows) [N]
    contact_state (N, n_c) int8            0 open/separated, 1 closed-or-stick, 2 slip
    periods int                            periods integrated (all runs together)
    steady bool, periodicity_error float   ‖period-end − period-start state‖∞ / amplitude
    input_work [J], damping_work [J]       ∮ f_eᵀ u̇ dt and ∮ u̇ᵀ D u̇ dt over the last period
    contact_work (n_c,) [J]                ∮ λᵀ dr per contact (friction dissipation ≥ 0)
    max_contact_iterations int             most Newton iterations any step needed
    section (P, 2 n_out) [m]               Poincaré section of the last run: the period-start state
                                           (u, u̇/ω at ``output_dofs``) of each of its P periods and
                                           the end state; a periodic orbit is one point, a 2T
                                           orbit alternates between two, a non-periodic response
                                           spreads (see :func:`section_spread`)
    final_state                            (u, u̇, sliders) at the end: the warm start of the next
                                           frequency (``initial=`` this response)
    """

    omega: float
    harmonics: int
    steps_per_period: int
    time: np.ndarray
    output_dofs: np.ndarray
    displacement: np.ndarray
    velocity: np.ndarray
    displacement_harmonics: np.ndarray
    contact_displacement: np.ndarray
    contact_force: np.ndarray
    contact_force_harmonics: np.ndarray
    contact_state: np.ndarray
    periods: int
    steady: bool
    periodicity_error: float
    input_work: float
    damping_work: float
    contact_work: np.ndarray
    max_contact_iterations: int
    section: np.ndarray | None = None
    final_state: tuple | None = None


def section_spread(section, tail=None, period=1):
    """Spread of a Poincaré section, relative to the response amplitude (dimensionless).

    section (P, m) from :class:`TimeResponse`; the last ``tail`` points are used (all by default).
    Returns max over components of (max − min) of every ``period``-th point, divided by the
    largest |component| of the tail: ≈ 0 for a T-periodic response (``period`` = 1) or for a
    k·T-periodic one with ``period`` = k; O(1) for a quasi-periodic or chaotic one.
    """
    x = np.asarray(section, dtype=float)
    if tail is not None:
        x = x[-int(tail):]
    scale = max(np.abs(x).max(initial=0.0), 1e-300)
    spreads = [np.ptp(x[j::period], axis=0).max(initial=0.0) for j in range(min(period, len(x)))]
    return float(max(spreads, default=0.0) / scale)


def linear_harmonic_response(model, excitation, omega, steps_per_period=None):
    """Periodic response of M ü + D u̇ + K u = f_e (contacts ignored), as harmonics (2H+1, n_dof) [m].

    Per harmonic k: (K − ω_k² M + i ω_k D) Û_k = F_kc − i F_ks, u_kc = Re Û_k, u_ks = −Im Û_k, with
    ω_k = kω (exact), or ω_k = (2/h) tan(kωh/2), h = 2π/(ωN), when ``steps_per_period`` N is given:
    the exact periodic solution of the Newmark average-acceleration scheme. A singular K (a DOF held
    only by contacts) gets the least-squares mean u0.
    """
    F = np.asarray(excitation, dtype=float)
    H = (F.shape[0] - 1) // 2
    M, D, K = model.mass, model.damping, model.stiffness
    dense = not sp.issparse(K)
    n_dof = K.shape[0]
    U = np.zeros(F.shape)
    for k in range(H + 1):
        w = _warped(k * omega, omega, steps_per_period)
        if k == 0:
            rhs = F[0].astype(complex)
        else:
            rhs = F[2 * k - 1] - 1j * F[2 * k]
        if not np.any(rhs):
            continue
        S = K - w * w * M + 1j * w * D
        if dense:
            Uk = np.linalg.lstsq(np.asarray(S, dtype=complex), rhs, rcond=None)[0]
        else:
            with warnings.catch_warnings():  # singular K (DOFs held by contacts only): zero mean
                warnings.simplefilter("ignore", spla.MatrixRankWarning)
                Uk = spla.spsolve(sp.csc_matrix(S, dtype=complex), rhs)
            if not np.all(np.isfinite(Uk)):
                Uk = np.zeros(n_dof, dtype=complex)
        if k == 0:
            U[0] = Uk.real
        else:
            U[2 * k - 1], U[2 * k] = Uk.real, -Uk.imag
    return U


def _warped(frequency, omega, steps_per_period):
    """Bilinear-transform frequency (2/h) tan(ω_k h/2) seen by the trapezoidal rule (or ω_k)."""
    if steps_per_period is None or frequency == 0:
        return frequency
    h = 2.0 * np.pi / (omega * steps_per_period)
    return 2.0 / h * np.tan(0.5 * frequency * h)


def _state_at_zero(U, omega, steps_per_period):
    """u(0) and the scheme-consistent v(0) of harmonics U (2H+1, n): v = Σ ω'_k u_ks."""
    H = (U.shape[0] - 1) // 2
    k = np.arange(1, H + 1)
    wk = np.array([_warped(kk * omega, omega, steps_per_period) for kk in k])
    u0 = U[0] + U[1::2].sum(axis=0)
    v0 = (wk[:, None] * U[2::2]).sum(axis=0) if H else np.zeros_like(U[0])
    return u0, v0


class _ContactLaws:
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
            jac[g["normal_rows"], g["normal_rows"]] = stiffness[has]
            if g["tangent"]:
                jac[g["pair_rows"], g["pair_cols"]] += keep["d_tq"][g["pair"]]
                if g["coupled_rows"].size:   # slip limit follows the normal force
                    d_tn = keep["d_tn"] * stiffness[g["t_sel"], None]
                    jac[g["coupled_rows"], g["coupled_cols"]] += d_tn[g["coupled"]]
        return jac


def _slider_from_initial(law, r0, initial_force):
    """Slider positions w = q − λ_t/k_t from a given contact force (or w = q: unloaded spring)."""
    slider = np.zeros((law.slider_count, 2))
    for g in law.groups:
        if not g["tangent"]:
            continue
        q = np.where(g["t_mask"], r0[g["t_safe"]], 0.0)
        force = None if initial_force is None else np.where(g["t_mask"],
                                                            initial_force[g["t_safe"]], 0.0)
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
        self.g = solve(forcing.T).T if forcing.shape[0] else forcing      # K_eff⁻¹ f_j, (N, n)
        rows_t = gap_map.T.toarray() if sp.issparse(gap_map) else gap_map.T
        self.B = solve(rows_t) if gap_map.shape[0] else np.zeros((n, 0))
        self.B = self.B.reshape(n, -1)
        self.C = np.asarray(gap_map @ self.B)                             # contact compliance

    def linear(self, u, v, a, j):
        if self.dense:
            return self.P @ np.concatenate((u, v, a)) + self.g[j]
        c0, c1, c2 = self.c
        return self.lu.solve(self.M @ (c0 * u + c1 * v + a) + self.D @ (c2 * u + v)) + self.g[j]


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


def _run(model, contacts, forcing, omega, N, u, v, slider, max_periods, steady_tolerance,
         accelerate, progress, period_offset, section_dofs=None):
    """Integrate whole periods from (u, v, slider) at t = 0 until periodic; returns a dict.

    With ``accelerate``, every few periods the period-start states are extrapolated to the fixed
    point of the period map (reduced-rank extrapolation); a jump that does not lower the
    periodicity error is undone, and the next try waits longer (off after 4 failures).
    """
    n = u.size
    h = 2.0 * np.pi / (omega * N)
    dense = n <= DENSE_LIMIT
    if contacts is None:
        G = np.zeros((0, n))
    else:  # dense rows for small (reduced) models, sparse matvecs for big ones
        G = contacts.gap_map.toarray() if dense else sp.csr_matrix(contacts.gap_map)
    law = _ContactLaws(contacts) if contacts is not None and contacts.count else None
    n_rows, n_c = G.shape[0], (contacts.count if contacts is not None else 0)
    prop = _Propagator(model, h, G, forcing)
    M, D, K = model.mass, model.damping, model.stiffness
    identity = np.eye(n_rows)
    if law is not None:  # round-off floor of the contact Newton [m]
        length_floor = law.length_floor(contacts.gap)
    rate = 2.0 / h       # Newmark: ṙ₊ = (2/h)(r₊ − r) − ṙ, ∂ṙ₊/∂r₊ = 2/h

    def contact(r_lin, slider_prev, r_guess, r_start, rdot_start):
        """Solve r + C λ(r, ṙ(r)) = r_lin (semismooth Newton); returns λ, slider, state, r,
        iterations."""
        r = r_guess
        tolerance = 1e-12 * np.abs(r_lin).max() + length_floor
        for it in range(1, 60):
            rdot = rate * (r - r_start) - rdot_start if law.velocity else None
            lam, new_slider, state = law.forces(r, rdot, slider_prev)
            residual = r + prop.C @ lam - r_lin
            if np.abs(residual).max() <= tolerance:
                break
            step = np.linalg.solve(identity + prop.C @ law.jacobian(rate), residual)
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
    section = []
    while periods < max_periods:
        start = pack(u, v, slider)
        section.append(np.concatenate((u[section_dofs], v[section_dofs] / omega)))
        r_prev = G @ u
        for j in range(N):
            u_samples[j], v_samples[j] = u, v
            r_samples[j], lam_samples[j] = r_prev, lam
            if n_c:
                state_samples[j] = state
            u_lin = prop.linear(u, v, a, (j + 1) % N)
            if law is not None:
                r_lin = G @ u_lin
                guess = r_lin - prop.C @ lam  # predictor: last step's contact force
                lam_new, slider, state, r_new, iterations = contact(
                    r_lin, slider, guess, r_prev, G @ v if law.velocity else None)
                worst_iterations = max(worst_iterations, iterations)
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
    du = np.diff(np.vstack((u_samples, u)), axis=0)
    input_work = float(np.sum(du * 0.5 * (forcing + np.roll(forcing, -1, axis=0))))
    damping_work = float(np.sum(du * (D @ du.T).T) / h)
    contact_work = np.sum(np.diff(np.vstack((r_samples, r_prev)), axis=0)
                          * 0.5 * (lam_samples + np.vstack((lam_samples[1:], lam))), axis=0)
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
        final=(u, v, slider),
        section=np.array(section + [np.concatenate((u[section_dofs], v[section_dofs] / omega))]),
    )


def integrate_time(model, contacts, excitation, omega, harmonics, steps_per_period=512,
                   max_periods=1000, steady_tolerance=1e-7, initial=None, *, output_dofs=None,
                   richardson=False, accelerate=True, progress=None) -> TimeResponse:
    """Periodic steady state of M ü + D u̇ + K u + Gᵀλ = f_e(t) by Newmark time integration.

    model: :class:`LinearModel` (n_dof); contacts: :class:`ContactSet` or None; excitation: force
    harmonics F (2H_e+1, n_dof) [N] at ``omega`` [rad/s]; harmonics: H of the returned analysis.
    steps_per_period: N, fixed step h = T/N (contacts need N ≳ 512 for 0.1 %).
    max_periods: cap on integrated periods (``steady`` is False when it is hit).
    steady_tolerance: relative change of the period-end state (u, u̇/ω, sliders) that ends the run.
    initial: start state — None (the scheme's linear periodic solution, contacts ignored), harmonics
    (2H'+1, n_dof) [m], a :class:`HarmonicSolution` (its ``displacement`` and θ = 0 contact force
    set the slider positions), or a :class:`TimeResponse` (its end state u, sliders and u̇·ω/ω_prev:
    a sweep warm-started from the previous frequency's final state).
    output_dofs: DOF indices kept in ``displacement``/``velocity`` samples (default: all DOFs, or
    only the DOFs the contacts touch when n_dof > DENSE_LIMIT). ``displacement_harmonics`` always
    covers all DOFs (the last period is held in memory, N × n_dof).
    richardson: also run with 2N steps and extrapolate the harmonics, (4 U_2N − U_N)/3 (the scheme's
    error is O(h²)); all other fields come from the 2N run.
    accelerate: extrapolate the period-start states to the periodic orbit every few periods
    (reduced-rank extrapolation of the period map; a jump that does not help is undone).
    progress: optional callable(periods_done, None).
    """
    F = np.asarray(excitation, dtype=float)
    n = model.dof_count
    if F.ndim != 2 or F.shape[1] != n or F.shape[0] % 2 != 1:
        raise ValueError(f"excitation must have shape (2H+1, {n}), got {F.shape}")
    if omega <= 0:
        raise ValueError(f"omega must be > 0, got {omega!r}")
    N = int(steps_per_period)
    if N < 2 * harmonics + 1:
        raise ValueError(f"steps_per_period must be >= 2H+1 = {2 * harmonics + 1}, got {N}")
    if contacts is not None and contacts.gap_map.shape[1] != n:
        raise ValueError(f"contacts.gap_map has {contacts.gap_map.shape[1]} columns, model has {n} DOFs")
    if output_dofs is None:  # all DOFs of reduced models; only the contact DOFs of big ones
        output_dofs = np.arange(n) if n <= DENSE_LIMIT or contacts is None else \
            np.unique(sp.csr_matrix(contacts.gap_map).indices)
    output_dofs = np.asarray(output_dofs, dtype=int)

    law = _ContactLaws(contacts) if contacts is not None and contacts.count else None
    initial_force = None
    warm = initial.final_state if isinstance(initial, TimeResponse) else None
    if warm is not None:   # the end state of another run (e.g. the previous frequency of a sweep)
        u_w, v_w, slider_w = (np.array(x, dtype=float) for x in warm)
        if u_w.shape != (n,) or slider_w.shape != (law.slider_count if law else 0, 2):
            raise ValueError(f"initial TimeResponse has a state of {u_w.size} DOFs / "
                             f"{slider_w.shape[0]} sliders, the model {n} DOFs")
        # same phase θ = 0 of the excitation; velocity scaled to the new ω (same orbit shape)
        v_w = v_w * (omega / initial.omega)
        U_init = None
    elif initial is None:
        U_init = linear_harmonic_response(model, F, omega, N)
    elif hasattr(initial, "displacement"):
        U_init = np.asarray(initial.displacement, dtype=float)
        force_time = getattr(initial, "contact_force_time", None)
        initial_force = None if force_time is None else np.asarray(force_time)[0]
    else:
        U_init = np.asarray(initial, dtype=float)
    if U_init is not None and (U_init.ndim != 2 or U_init.shape[1] != n):
        raise ValueError(f"initial harmonics must have shape (2H+1, {n}), got {U_init.shape}")

    def one_run(N_run, u, v, slider, offset):
        forcing = time_samples(F, N_run)
        return _run(model, contacts, forcing, omega, N_run, u, v, slider, max_periods,
                    steady_tolerance, accelerate, progress, offset, output_dofs)

    if warm is not None:
        u0, v0, slider0 = u_w, v_w, slider_w
    else:
        u0, v0 = _state_at_zero(U_init, omega, N)
        G = contacts.gap_map if contacts is not None else None
        slider0 = _slider_from_initial(law, G @ u0, initial_force) if law is not None \
            else np.zeros((0, 2))
    run = one_run(N, u0, v0, slider0, 0)
    U = harmonic_coefficients(run["u"], harmonics)
    periods, steady = run["periods"], run["steady"]
    if richardson:
        U_coarse = U
        u_end, _, slider_end = run["final"]
        # restart with the coarse periodic orbit, velocity re-derived for the finer scheme
        _, v_fine = _state_at_zero(U_coarse, omega, 2 * N)
        run = one_run(2 * N, u_end, v_fine, slider_end, periods)
        N = 2 * N
        U_fine = harmonic_coefficients(run["u"], harmonics)
        U = (4.0 * U_fine - U_coarse) / 3.0
        periods += run["periods"]
        steady = steady and run["steady"]
    lam = run["lam"]
    return TimeResponse(
        omega=float(omega),
        harmonics=int(harmonics),
        steps_per_period=N,
        time=np.arange(N) * (2.0 * np.pi / omega / N),
        output_dofs=output_dofs,
        displacement=run["u"][:, output_dofs],
        velocity=run["v"][:, output_dofs],
        displacement_harmonics=U,
        contact_displacement=run["r"],
        contact_force=lam,
        contact_force_harmonics=harmonic_coefficients(lam, harmonics),
        contact_state=run["state"],
        periods=periods,
        steady=bool(steady),
        periodicity_error=float(run["error"]),
        input_work=float(run["input_work"]),
        damping_work=float(run["damping_work"]),
        contact_work=run["contact_work"],
        max_contact_iterations=int(run["iterations"]),
        section=run["section"],
        final_state=run["final"],
    )


def integrate_transient(model, contacts, displacement, velocity, duration, steps):
    """Free response (no excitation) from a given state over ``duration`` [s] in ``steps`` Newmark
    steps, with the same contact handling as :func:`integrate_time` (e.g. a single impact).

    displacement, velocity: u(0) [m], u̇(0) [m/s] (n_dof,). Returns a dict: time (steps,) [s]
    t_j = j·duration/steps, displacement, velocity (steps, n_dof), contact_displacement,
    contact_force (steps, n_rows), and the state at t = duration: final_displacement,
    final_velocity (n_dof,).
    """
    n = model.dof_count
    N = int(steps)
    omega = 2.0 * np.pi / float(duration)
    law = _ContactLaws(contacts) if contacts is not None and contacts.count else None
    u0 = np.asarray(displacement, dtype=float).reshape(n)
    v0 = np.asarray(velocity, dtype=float).reshape(n)
    slider = _slider_from_initial(law, contacts.gap_map @ u0, None) if law is not None \
        else np.zeros((0, 2))
    run = _run(model, contacts, np.zeros((N, n)), omega, N, u0, v0, slider, 1, 0.0, False, None, 0)
    u_end, v_end, _ = run["final"]
    return {"time": np.arange(N) * (float(duration) / N), "displacement": run["u"],
            "velocity": run["v"], "contact_displacement": run["r"], "contact_force": run["lam"],
            "final_displacement": u_end, "final_velocity": v_end}


def period_work(displacement_harmonics, excitation, damping, contact_displacement_harmonics,
                contact_force_harmonics, omega):
    r"""Work per period from harmonics (Parseval), for the energy balance of a periodic solution.

    With u̇ = ω ∇ U and ∫₀ᵀ a b dt = T (a₀b₀ + ½ Σ_k a_kc b_kc + a_ks b_ks):
    returns (input ∮ f_eᵀ u̇ dt, viscous ∮ u̇ᵀ D u̇ dt, contact ∮ λ ṙ dt per row (n_rows,)) [J].
    Periodic balance: input = viscous + Σ contact (penalty rows give 0, friction rows dissipate).
    """
    from sarfe.hbm.harmonics import derivative_matrix

    U = np.asarray(displacement_harmonics, dtype=float)
    H = (U.shape[0] - 1) // 2
    F = np.zeros_like(U)
    Fe = np.asarray(excitation, dtype=float)
    m = min(F.shape[0], Fe.shape[0])
    F[:m] = Fe[:m]
    nabla = derivative_matrix(H)
    period = 2.0 * np.pi / omega
    weight = np.full(2 * H + 1, 0.5)
    weight[0] = 1.0
    V = omega * nabla @ U
    input_work = period * np.sum(weight[:, None] * F * V)
    DV = (damping @ V.T).T
    damping_work = period * np.sum(weight[:, None] * V * DV)
    R = np.asarray(contact_displacement_harmonics, dtype=float)
    L = np.asarray(contact_force_harmonics, dtype=float)
    Hr = (R.shape[0] - 1) // 2
    Rdot = omega * derivative_matrix(Hr) @ R
    wr = np.full(2 * Hr + 1, 0.5)
    wr[0] = 1.0
    contact_work = period * np.sum(wr[:, None] * L[: 2 * Hr + 1] * Rdot, axis=0)
    return float(input_work), float(damping_work), contact_work
