r"""Time integration of the contact model to its periodic steady state (the HBM's independent check).

Equation (the same model as the harmonic balance, see :mod:`sarfe.hbm.contacts`)

    M ü + D u̇ + K u + Gᵀ λ(G u, history) = f_e(t),
    f_e(t) = F0 + Σ_k F_kc cos kωt + F_ks sin kωt        (F = ``excitation``, (2H+1, n_dof) [N])

integrated by the Newmark average-acceleration scheme with a fixed step h = T/N and the contact
laws evaluated pointwise in time (:mod:`sarfe.hbm.newmark`: the step, its contact Newton on the
contact rows, the friction return map, sub-steps where a stiff contact opens or closes).
:func:`integrate_time` runs periods until the period-end state (u, v/ω, sliders) repeats to
``steady_tolerance`` (relative to the response amplitude) and Fourier-analyses the last period
with the convention of :mod:`sarfe.hbm.harmonics`; :func:`integrate_transient` is a free response
from a given state.

For a linear system the scheme's periodic response is the exact one at the warped frequencies
ω'_k = (2/h) tan(kωh/2) (bilinear transform), so its amplitude error is O((ωh)²). The run starts
from that discrete linear periodic solution (:func:`linear_harmonic_response`; or from a given HBM
solution), which removes the transient of the linear part. :func:`period_work` is the energy
balance of a periodic solution from its harmonics (Parseval).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from sarfe.hbm.harmonics import derivative_matrix, harmonic_coefficients, time_samples
from sarfe.hbm.newmark import (DENSE_LIMIT, ContactLaws, initial_sliders, march_periods,
                               state_at_zero, warped_frequency)

__all__ = ["TimeResponse", "integrate_time", "integrate_transient", "linear_harmonic_response",
           "period_work", "section_spread"]


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
    substepped_steps int                   steps of the last period redone in sub-steps (a stiff
                                           contact opened or closed in them)
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
    substepped_steps: int = 0


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
    only by contacts) gets the least-squares mean u0. Dense: one LU per harmonic
    (:func:`_dense_solve`; the SVD-based least squares only for a singular or ill-conditioned
    matrix: ≈ 10× cheaper for a Craig–Bampton model of 600 DOFs, the same solution).
    """
    F = np.asarray(excitation, dtype=float)
    H = (F.shape[0] - 1) // 2
    M, D, K = model.mass, model.damping, model.stiffness
    dense = not sp.issparse(K)
    n_dof = K.shape[0]
    U = np.zeros(F.shape)
    for k in range(H + 1):
        w = warped_frequency(k * omega, omega, steps_per_period)
        if k == 0:
            rhs = F[0].astype(complex)
        else:
            rhs = F[2 * k - 1] - 1j * F[2 * k]
        if not np.any(rhs):
            continue
        S = K - w * w * M + 1j * w * D
        if dense:
            Uk = _dense_solve(np.asarray(S, dtype=complex), rhs)
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


def _dense_solve(S, rhs):
    """S⁻¹ b (S (n, n) dense complex) by LU where that is the least-squares solution
    np.linalg.lstsq(S, b, rcond=None) gives: S regular with σ_min/σ_max > n ε (lstsq truncates
    no singular value), which holds when LAPACK's 1-norm estimate rcond₁ > n² ε
    (σ_min/σ_max ≥ rcond₁/n). Otherwise (singular or ill-conditioned, or a non-finite LU result)
    the least squares itself."""
    n = S.shape[0]
    lu, piv, info = _getrf(S)
    if info == 0:
        rcond, info = _gecon(lu, np.abs(S).sum(axis=0).max(), norm="1")
        if info == 0 and rcond > n * n * np.finfo(float).eps:
            x, info = _getrs(lu, piv, rhs)
            if info == 0 and np.all(np.isfinite(x)):
                return x
    return np.linalg.lstsq(S, rhs, rcond=None)[0]


_getrf, _gecon, _getrs = sla.get_lapack_funcs(("getrf", "gecon", "getrs"), dtype=complex)


def integrate_time(model, contacts, excitation, omega, harmonics, steps_per_period=512,
                   max_periods=1000, steady_tolerance=1e-7, initial=None, *, output_dofs=None,
                   richardson=False, accelerate=True, progress=None) -> TimeResponse:
    """Periodic steady state of M ü + D u̇ + K u + Gᵀλ = f_e(t) by Newmark time integration.

    model: :class:`LinearModel` (n_dof); contacts: :class:`ContactSet` or None; excitation: force
    harmonics F (2H_e+1, n_dof) [N] at ``omega`` [rad/s]; harmonics: H of the returned analysis.
    steps_per_period: N, fixed step h = T/N (contacts need N ≳ 512 for 0.1 %); a step in which a
    stiff contact opens or closes is redone in sub-steps (:mod:`sarfe.hbm.newmark`).
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

    law = ContactLaws(contacts) if contacts is not None and contacts.count else None
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
        return march_periods(model, contacts, forcing, omega, N_run, u, v, slider, max_periods,
                             steady_tolerance, accelerate, progress, offset, output_dofs)

    if warm is not None:
        u0, v0, slider0 = u_w, v_w, slider_w
    else:
        u0, v0 = state_at_zero(U_init, omega, N)
        G = contacts.gap_map if contacts is not None else None
        slider0 = initial_sliders(law, G @ u0, initial_force) if law is not None \
            else np.zeros((0, 2))
    run = one_run(N, u0, v0, slider0, 0)
    U = harmonic_coefficients(run["u"], harmonics)
    periods, steady = run["periods"], run["steady"]
    if richardson:
        U_coarse = U
        u_end, _, slider_end = run["final"]
        # restart with the coarse periodic orbit, velocity re-derived for the finer scheme
        _, v_fine = state_at_zero(U_coarse, omega, 2 * N)
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
        substepped_steps=int(run["substeps"]),
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
    law = ContactLaws(contacts) if contacts is not None and contacts.count else None
    u0 = np.asarray(displacement, dtype=float).reshape(n)
    v0 = np.asarray(velocity, dtype=float).reshape(n)
    slider = initial_sliders(law, contacts.gap_map @ u0, None) if law is not None \
        else np.zeros((0, 2))
    run = march_periods(model, contacts, np.zeros((N, n)), omega, N, u0, v0, slider, 1, 0.0, False,
                        None, 0)
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
