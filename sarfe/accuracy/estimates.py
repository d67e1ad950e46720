r"""Accuracy as an input: cheap a-posteriori error estimates of a harmonic-balance solution.

A solution ũ (2H+1, n) at ω solves R_{H,N}(ũ) = S(ω) ũ + f̃_nl^{(N)}(ũ) − f̃_e = 0. Embedded in a richer
discretization (H', N') it leaves a residual R_{H',N'}(ũ) ≠ 0; Newton iterations of the richer problem
from there, the first being

    δ = −J_{H',N'}(ũ)⁻¹ R_{H',N'}(ũ),                                           (1)

give the change of the solution when H → H' (harmonic truncation) or N → N' = 2N (AFT aliasing).
From a start this close they take one to a few iterations (condensed on the contact rows); H is
raised to H' in steps of ×1.5 so that impacts, whose active set a large step changes, converge, and
when a raise does not, the change up to the last converged H'' is used (noted). The changes are
measured on the quantities users read:

- ``amplitude_rel``: max over contact rows of |Δ a₁| / max a₁, a₁ = first-harmonic amplitude of r = G u;
- ``erp_db``: 10 log₁₀(P(ũ')/P(ũ)), P = Σ_k (kω)² Σ_s a_s |w_{s,k}|² (ERP ∝ normal velocity²,
  w = E ũ the radiating normal displacements, a_s their areas; all DOFs with unit areas when no E),
  or the same change of the A-weighted P_A (harmonic k weighted by 10^{A(kf)/10}) when larger: on
  impacts the high harmonics carry the dB(A) level, which converges more slowly in H.

Cheaper still and model-free (no solve at all) are the spectral tails

    tail(X) = ‖X_{k > H − m}‖ / ‖X_{k ≥ 1}‖,  m = max(1, ⌊H/4⌋)                   (2)

of the contact displacements and forces (energy in the highest kept harmonics), reported only.

H' is one doubling, 2H, at least H + 4 (two more odd orders: a friction contact that does not lift
off is nearly odd-symmetric) and, when the model's natural frequencies are known, at least the order
past its highest mode (:func:`reach_harmonics`): an impact's harmonic k that excites a plate mode at
k f carries most of the ERP, and only above the highest mode is the response mass-controlled and the
decay regular. With an error that decays like e(H) ≈ C H^{−p}, the change to H' is
d = e(H) − e(H') = (1 − (H/H')^p) e(H), so

    e(H) ≈ d / (1 − (H/H')^p) ≤ max(2, 1 / (1 − H/H')) d   for p ≥ 1           (3)

(Richardson; :func:`harmonics_richardson` — an extension beyond the doubling does not lower the
factor below 2, as the decay below the highest mode is not yet the asymptotic one). p ≥ 1 holds for
the contact laws here: the penalty (rattle) force is continuous with a kink at contact onset and the
Jenkins (squeak) force is continuous with kinks at stick/slip, so its Fourier coefficients decay like
k⁻² and the displacements faster. The factor RICHARDSON = 2 multiplies the N → 2N change too
(aliasing errors of kinked forces decay like N⁻², 1/(1 − 2⁻²) < 2).

Modal truncation of a Craig–Bampton model (coordinates [q_b, q_m, q_r]: boundary DOFs, fixed-interface
modes, residual modes — the modal ones in increasing frequency): the coarser model the same reduction
would give with the top fraction q of the modes (at least one) left out — those modes and the residual
modes replaced by the static responses of their span to the loads the residual modes stand for
(:func:`coarser_basis`), the modal damping rebuilt on its own eigenmodes — is solved (1) from the
solution projected on it. Its change d of a₁ and of the ERP level is the error of the coarser model
minus that of the kept one; with an error ∝ m^{−p} in the mode count m (:func:`mode_richardson`)

    e(m) = d / ((m/m')^p − 1)                                                       (4)

Two probes, q = 1/20 and 1/5 (MODE_PROBES), give d₁, d₂ with m₁' = 19m/20, m₂' = 4m/5; p is fitted
from d₂/d₁ = (r₂^p − 1)/(r₁^p − 1), r_i = m/m_i', kept in [1, 2.5] (MODE_DECAY), and

    modal_rel, modal_db = d₂ / (r₂^p − 1)                                           (5)

(:func:`modal_extrapolation`, separately for a₁ and the level). p = 1 is the slowest decay the modal density of a plate allows (the
factors 19 and 4); the cap 2.5 is conservative against the measured decay: from 0.75 to 1.0 H f_max
the true changes fall ≈ 10× (p ≈ 8 in m) on the door trim (benchmarks/results/cutoff.md). A single
probe of the top fifth with p = 1 (the earlier rule, (5) with p = 1: never exceeded) probes ≈ 0.8 H f_max from a cutoff of H f_max,
where the top harmonics lose their nearly resonant modes, and over-reported up to 35× (with the
floor below). Against the measured changes (benchmarks/results/modal_estimate.md: door trim
15/10/5 mm at 0.75 and 1.0 H f_max, demo case at 1.0 and 1.25, 44 points) (5) plus the floor
brackets every point, the closest 1.4× (amplitude) / 2.2× (dB), and over-reports at H f_max by
≤ 12× (amplitude and dB). It costs two small re-solves instead of one (≈ 0.02 s each at 5 mm, ≈ 1 % of a
point) and builds two coarser models per stage.
It is the only part that sees the modes at the contact DOFs: those are boundary DOFs, whose
coordinates a truncation without re-solving would not change.

``amplitude_rel`` = (3)·harmonics_rel + 2·aliasing_rel + modal_rel + AMPLITUDE_FLOOR, likewise
``erp_db`` (+ ERP_FLOOR_DB) (triangle inequality over the three sources; harmonics_rel,
aliasing_rel are the raw changes, modal_rel already includes its factor; the floors, only where a
contact carries force, are the estimate's resolution: on the stuck-friction points of the FE cases
the true errors are 5e-5 amplitude and 1e-4 dB, below what the parts resolve). benchmarks/results/accuracy.md compares them with the true error on every
shipped case.

An ERP level error of ε_dB corresponds to a relative amplitude error 10^{ε_dB/20} − 1 (0.5 dB ≈ 5.9 %).
"""
from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np

RICHARDSON = 2.0   # 1 / (1 − 2^{−p}) for an error ∝ H^{−p}, p = 1, and one doubling (3)
REFINE_ITERATIONS = 40  # Newton iterations allowed per raise of H (1) before stopping the climb
MAX_EXTENSION = 64      # cap of H' in :func:`reach_harmonics`
AMPLITUDE_FLOOR = 1e-4       # added to every estimate of a point with an active contact: the
ERP_FLOOR_DB = 0.01          # estimate's resolution (stuck-friction points of the FE cases have
                             # true errors 5e-5 / 1e-4 dB that no part resolves)
ESTIMATE_ITERATIONS = 8      # Newton iterations of one estimate solve (1) (usually 1–4)
ESTIMATE_TOLERANCE = 1e-7    # its relative residual: the changes sought are ≥ 1e-4 of a₁
STALLED_RESIDUAL = 1e-5      # a solve stalled below this residual (at a kink) is still used
MODE_PROBES = (0.05, 0.2)    # fractions of the fixed-interface modes the two modal probes leave out (5)
MODE_DECAY = (1.0, 2.5)      # bounds of the fitted decay p of the modal error ∝ m^{−p} (5)

PRESETS = {   # ERP of impacts converges slowly in H (ERP ∝ Σ (kω)² |w_k|²): dB targets are looser
    "fast": {"amplitude_rel": 5e-2, "erp_db": 2.0},
    "balanced": {"amplitude_rel": 1e-2, "erp_db": 0.5},
    "fine": {"amplitude_rel": 1e-3, "erp_db": 0.1},
}


@dataclass(frozen=True)
class AccuracyTarget:
    """What the user asks for: relative first-harmonic amplitude error and/or ERP level error [dB]."""

    amplitude_rel: float | None = None
    erp_db: float | None = None
    name: str = ""

    def amplitude_budget(self) -> float:
        """Relative amplitude error allowed (the stricter of both targets)."""
        values = []
        if self.amplitude_rel is not None:
            values.append(self.amplitude_rel)
        if self.erp_db is not None:
            values.append(10 ** (self.erp_db / 20.0) - 1.0)
        return min(values) if values else PRESETS["balanced"]["amplitude_rel"]

    def met_by(self, amplitude_rel: float, erp_db: float, share: float = 1.0) -> bool:
        ok = True
        if self.amplitude_rel is not None:
            ok &= bool(amplitude_rel <= share * self.amplitude_rel)
        if self.erp_db is not None:
            ok &= bool(abs(erp_db) <= share * self.erp_db)
        if self.amplitude_rel is None and self.erp_db is None:
            ok &= bool(amplitude_rel <= share * self.amplitude_budget())
        return ok


def parse_accuracy(value) -> AccuracyTarget:
    """'fast' | 'balanced' | 'fine' | {'erp_db': x} | {'amplitude_rel': x} | 'erp_db=0.5' → target.

    Raises ValueError naming the problem.
    """
    if isinstance(value, AccuracyTarget):
        return value
    if isinstance(value, str):
        text = value.strip()
        if text in PRESETS:
            return AccuracyTarget(**PRESETS[text], name=text)
        if "=" in text:
            key, _, number = text.partition("=")
            return parse_accuracy({key.strip(): float(number)})
        raise ValueError(f"accuracy must be one of {sorted(PRESETS)} or {{erp_db: x}} / "
                         f"{{amplitude_rel: x}}, got {value!r}")
    if isinstance(value, dict):
        unknown = set(value) - {"erp_db", "amplitude_rel"}
        if unknown or not value:
            raise ValueError(f"accuracy accepts the keys erp_db and amplitude_rel, got {sorted(value)}")
        for key, number in value.items():
            if not (isinstance(number, (int, float)) and math.isfinite(number) and number > 0):
                raise ValueError(f"accuracy.{key} must be a number > 0, got {number!r}")
        name = ", ".join(f"{k}={v:g}" for k, v in value.items())
        return AccuracyTarget(value.get("amplitude_rel"), value.get("erp_db"), name)
    raise ValueError(f"accuracy: unsupported value {value!r}")


@dataclass(frozen=True)
class ErrorEstimate:
    """Error estimates of one solution (module docstring). NaN where not computed.

    harmonics_rel / harmonics_db: H → ``extended_harmonics`` (1); aliasing_rel / aliasing_db:
    N → 2N (1); modal_rel / modal_db: two probes of the top modes removed, extrapolated (4, 5);
    displacement_tail / force_tail: (2).
    amplitude_rel, erp_db: RICHARDSON × (harmonics + aliasing part) + modal part (3), (4) (what
    the run's accuracy check compares with the target). seconds: time spent estimating.
    basis_top_hz: the highest fixed-interface mode of a Craig–Bampton model [Hz] (NaN otherwise):
    harmonics of the H' re-solve above it are answered by the residual vectors, whose Ritz
    frequencies sit just above it — there the reduced model's own error enters the harmonics
    change (:func:`basis_limited_extension`).
    """

    harmonics: int
    samples_per_period: int
    extended_harmonics: int
    harmonics_rel: float
    harmonics_db: float
    aliasing_rel: float
    aliasing_db: float
    modal_rel: float
    modal_db: float
    displacement_tail: float
    force_tail: float
    amplitude_rel: float
    erp_db: float
    seconds: float = 0.0
    notes: tuple = field(default=())
    basis_top_hz: float = float("nan")

    def as_dict(self) -> dict:
        data = asdict(self)
        data["notes"] = list(self.notes)
        return data


# ------------------------------------------------------------------------------------- helpers
def resize_harmonics(U, harmonics: int) -> np.ndarray:
    """Coefficients (2H+1, ...) → (2H'+1, ...): truncate or pad with zeros."""
    U = np.asarray(U, dtype=float)
    rows = 2 * int(harmonics) + 1
    out = np.zeros((rows,) + U.shape[1:])
    m = min(rows, U.shape[0])
    out[:m] = U[:m]
    return out


def spectral_tail(X, top=None) -> float:
    """(2): share of the energy of harmonics k ≥ 1 in the top ``top`` harmonics (default ⌊H/4⌋, ≥ 1)."""
    X = np.asarray(X, dtype=float)
    H = (X.shape[0] - 1) // 2
    if H < 1:
        return 0.0
    top = max(1, H // 4) if top is None else int(top)
    energy = (X[1:].reshape(H, 2, -1) ** 2).sum(axis=(1, 2))
    total = energy.sum()
    if not total > 0:
        return 0.0
    return float(np.sqrt(energy[H - top:].sum() / total))


def harmonic_energy(X) -> np.ndarray:
    """Energy per harmonic order k = 0…H of coefficients (2H+1, ...): (H+1,) (k = 0: the mean²)."""
    X = np.asarray(X, dtype=float)
    H = (X.shape[0] - 1) // 2
    out = np.empty(H + 1)
    out[0] = (X[0] ** 2).sum()
    out[1:] = (X[1:].reshape(H, 2, -1) ** 2).sum(axis=(1, 2))
    return out


def _first_harmonic_amplitude(contacts, U):
    G = contacts.gap_map
    if G.shape[0] == 0:
        return np.zeros(0)
    return np.hypot(G @ U[1], G @ U[2])


def _harmonic_powers(U, omega, erp_map=None, erp_areas=None):
    """p_k = (kω)² Σ_s a_s |w_{s,k}|² (H,) (the ERP of harmonic k up to ½ρc): by the reduced
    quadratic form Q = Nᵀ diag(a) N (:mod:`sarfe.erp.reduced`, built once per map) when a
    radiating map N is given, else over all DOFs with unit areas."""
    from sarfe.erp.reduced import harmonic_power_proxy, radiation_gram

    U = np.asarray(U, dtype=float)
    if erp_map is None:
        areas = np.ones(U.shape[1]) if erp_areas is None else np.asarray(erp_areas, dtype=float)
        rows = (U[1:] ** 2) @ areas
        return (np.arange(1, rows.size // 2 + 1) * omega) ** 2 * (rows[0::2] + rows[1::2])
    areas = np.ones(erp_map.shape[0]) if erp_areas is None else erp_areas
    return harmonic_power_proxy(U, omega, radiation_gram(erp_map, areas))


def _erp_proxy(U, omega, erp_map=None, erp_areas=None, a_weighted=False, powers=None):
    """P = Σ_k (kω)² Σ_s a_s |w_{s,k}|² (proportional to the ERP of all harmonics); with
    ``a_weighted`` each harmonic k weighted by 10^{A(k f)/10}, A the A-weighting [dB] at k f,
    f = ω / 2π (proportional to the A-weighted ERP, which on impacts the high harmonics carry).
    ``powers``: :func:`_harmonic_powers` of U when computed already."""
    p = _harmonic_powers(U, omega, erp_map, erp_areas) if powers is None else powers
    if a_weighted:
        from sarfe.erp.weighting import a_weighting_db

        k = np.arange(1, p.size + 1)
        p = p * 10.0 ** (np.asarray(a_weighting_db(k * omega / (2 * np.pi))) / 10.0)
    return float(p.sum())


def _change(contacts, U, U_new, omega, erp_map, erp_areas, ref_amplitude=None):
    """(relative first-harmonic amplitude change at the contacts, ERP level change [dB])."""
    a0 = _first_harmonic_amplitude(contacts, U)
    a1 = _first_harmonic_amplitude(contacts, U_new)
    scale = np.max(a0, initial=0.0) if ref_amplitude is None else ref_amplitude
    if a0.size and scale > 0:
        rel = float(np.max(np.abs(a1 - a0)) / scale)
    else:  # no contact rows: use the largest DOF
        d0 = np.hypot(U[1], U[2])
        d1 = np.hypot(U_new[1], U_new[2])
        rel = float(np.max(np.abs(d1 - d0)) / max(d0.max(initial=0.0), 1e-300))
    q0 = _harmonic_powers(U, omega, erp_map, erp_areas)
    q1 = _harmonic_powers(U_new, omega, erp_map, erp_areas)
    p0, p1 = float(q0.sum()), float(q1.sum())
    if erp_map is not None:
        # a radiating surface that is silent compared with the structure (power ratio < 1e-24,
        # amplitude < 1e-12: round-off) has no meaningful level change
        whole = _erp_proxy(U, omega) * (np.sum(erp_areas) if erp_areas is not None else 1.0)
        if max(p0, p1) <= 1e-24 * whole:
            return rel, 0.0

    def level_change(p0, p1):
        return float(10 * np.log10(p1 / p0)) if p0 > 0 and p1 > 0 else (
            0.0 if p0 == p1 else float("inf"))

    db = level_change(p0, p1)
    db_a = level_change(_erp_proxy(U, omega, a_weighted=True, powers=q0),
                        _erp_proxy(U_new, omega, a_weighted=True, powers=q1))
    return rel, (db_a if abs(db_a) > abs(db) else db)      # the larger of dB and dB(A)


def newton_correction(model, contacts, excitation, solution, harmonics, samples_per_period,
                      options=None, robust=False):
    """(1) climbing: the solution of the (H', N') problem from ũ embedded in it, H raised to H' in
    steps of ×1.5 (N ≥ 4H + 1, retried with N/H kept when a step stalls), each a
    :func:`newton_step` warm-started from the last → (2H''+1, n) [m], H'' ≤ H'. The fallback when
    one solve at H' does not converge (an impact whose active set a large raise changes a lot);
    the climb stops at the last converged H''. None when no raise converges. excitation f̃_e
    (2H_e+1, n) [N] (resized). ``robust``: each raise by the engine's own solve (full line search,
    REFINE_ITERATIONS, the full-DOF fallback) instead of :func:`newton_step` — slower, the last
    resort."""
    H0, H_target = int(solution.harmonics), int(harmonics)
    N = int(samples_per_period)
    omega = float(solution.omega)
    steps = [H_target] if H_target <= H0 else []
    H = H0
    while H < H_target:
        H = min(H_target, max(H + 2, int(round(1.5 * H))))
        steps.append(H)
    best = None
    previous = np.asarray(solution.displacement, dtype=float)
    for H in steps:     # N ≥ 4H + 1; a stalled raise is tried once more with N/H kept
        first = N if H_target <= H0 else samples_for(H, N)
        scaled = N if H_target <= H0 else _at_least(N, max(4 * H + 1, N * H / max(H0, 1)))
        refined = None
        for N_try in (first, scaled) if scaled != first else (first,):
            if robust:
                refined = _engine_solve(model, contacts, resize_harmonics(excitation, H),
                                        resize_harmonics(previous, H), omega, H, N_try, options)
            else:
                refined = newton_step(model, contacts, resize_harmonics(excitation, H),
                                      resize_harmonics(previous, H), omega, H, N_try, options)
            if refined is not None:
                break
        if refined is None:
            break
        best = previous = refined
    return best


def _engine_solve(model, contacts, excitation, U, omega, harmonics, samples_per_period, options):
    """ũ of :func:`sarfe.hbm.solve_frequency` from U (at most REFINE_ITERATIONS), None if it fails."""
    from dataclasses import replace

    from sarfe.hbm.solve import SolverOptions, solve_frequency

    import warnings

    quick = replace(options or SolverOptions(), max_iterations=REFINE_ITERATIONS, stability=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            s = solve_frequency(model, contacts, excitation, omega, harmonics, samples_per_period,
                                initial=U, options=quick)
        except (ValueError, np.linalg.LinAlgError):
            return None
    U_new = np.asarray(s.displacement, dtype=float)
    return U_new if s.converged and np.all(np.isfinite(U_new)) else None


def newton_step(model, contacts, excitation, U, omega, harmonics, samples_per_period,
                options=None, steps=None):
    """The (H', N') problem solved from ũ (2H'+1, n) [m] by Newton (1), condensed on the contact
    rows as the engine solves it (x = G ũ; one condensation S_k(ω)⁻¹ Gᵀ at ω for every iteration;
    ũ recovered from the contact forces at the end) → ũ' (2H'+1, n), or None when the Jacobian is
    singular, Newton stalls above STALLED_RESIDUAL or ũ' is not finite. ``steps``: at most that
    many iterations (default ESTIMATE_ITERATIONS, relative residual ESTIMATE_TOLERANCE, at most 3
    line-search halvings); from a start this close they are usually 1–4."""
    from dataclasses import replace

    from sarfe.hbm.newton import SingularJacobian, newton
    from sarfe.hbm.solve import (SolverOptions, initial_slider, make_evaluator, make_problem,
                                 slider_acceptor)

    import warnings

    U = np.asarray(U, dtype=float)
    base = options or SolverOptions()
    options = replace(base, stability=False, max_iterations=int(steps or ESTIMATE_ITERATIONS),
                      tolerance=max(base.tolerance, ESTIMATE_TOLERANCE),
                      line_search_steps=min(base.line_search_steps, 3))
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        problem = make_problem(model, contacts, excitation, harmonics, samples_per_period, options)
        try:
            evaluate, to_x, to_displacement = make_evaluator(problem, contacts.row_count > 0, False)
            state = {"slider": initial_slider(problem, U)}
            result = newton(lambda x, jacobian: evaluate(x, omega, jacobian, state["slider"]),
                            to_x(U), options, accept=slider_acceptor(state), chord=True)
            if not (result.converged or result.residual_norm <= STALLED_RESIDUAL):
                return None     # (stalled at a kink of the sampled forces close by: kept)
            U_new = np.asarray(to_displacement(result.x, omega, result.evaluation))
        except SingularJacobian:
            return None
    U_new = U_new.reshape(U.shape)
    return U_new if np.all(np.isfinite(U_new)) else None


def extended_harmonics(harmonics: int) -> int:
    """H' used for the truncation estimate: 2H (one doubling, (3)) and at least H + 4, so that the
    next two odd orders are in (a friction contact that does not lift off is nearly odd-symmetric:
    its even harmonics vanish, and a step to H + 1 or 2H = 2 would add none)."""
    return int(max(2 * harmonics, harmonics + 4))


def reach_harmonics(harmonics: int, omega: float, highest_mode_hz=None) -> int:
    """H' for a model with natural frequencies up to ``highest_mode_hz``: :func:`extended_harmonics`
    and at least the order ⌈f_top / f⌉ + 1 that passes the highest mode (capped at MAX_EXTENSION).
    Harmonics below a mode can be resonant — an impact's harmonic k exciting a plate mode at k f
    carries most of the ERP — so an estimate that stops short of them misses them; above the
    highest mode the response is mass-controlled (G S_k⁻¹ Gᵀ ∝ (kω)⁻², w_k ≈ λ_k / (k ω)²) and the
    decay that (3) assumes holds."""
    H_ext = extended_harmonics(harmonics)
    if highest_mode_hz is None or not np.isfinite(highest_mode_hz) or omega <= 0:
        return H_ext
    reach = int(math.ceil(2 * np.pi * float(highest_mode_hz) / float(omega))) + 1
    return int(max(H_ext, min(MAX_EXTENSION, reach)))


def coarser_basis(model, excitation, boundary_count, removed, residual=()):
    """T (n, n') of the coarser Craig–Bampton model (4): the coordinates ``removed`` and
    ``residual`` (the residual modes) are replaced by the static responses of the set S they span to
    the loads the residual modes stand for — unit boundary accelerations (columns M_Sb) and the
    excitation (f̃_e,S, cosine and sine rows) —

        W = K_SS⁻¹ [M_Sb, f_S],  M-orthonormalized (rank-revealing),

    i.e. the basis a reduction with the modes ``removed`` left out would have built (its residual
    modes). Without residual modes the removed coordinates are just dropped. The boundary DOFs are
    the first ``boundary_count`` coordinates."""
    n = model.dof_count
    removed = np.asarray(removed, dtype=int)
    residual = np.asarray(residual, dtype=int)
    S = np.concatenate([removed, residual])
    keep = np.setdiff1d(np.arange(n), S)
    blocks = [np.eye(n)[:, keep]]
    if residual.size:
        dense = (lambda A: A.toarray() if hasattr(A, "toarray") else np.asarray(A, dtype=float))
        M, K = dense(model.mass), dense(model.stiffness)
        boundary = np.arange(int(boundary_count))
        F = np.asarray(excitation, dtype=float)
        loads = np.column_stack([M[np.ix_(S, boundary)], F[1, S], F[2, S]])
        W0 = np.linalg.solve(K[np.ix_(S, S)], loads)
        gram = W0.T @ M[np.ix_(S, S)] @ W0
        values, vectors = np.linalg.eigh(0.5 * (gram + gram.T))
        ok = values > 1e-10 * max(values.max(initial=0.0), 1e-300)
        W = np.zeros((n, int(ok.sum())))
        W[S] = W0 @ vectors[:, ok] / np.sqrt(values[ok])
        blocks.append(W)
    return np.column_stack(blocks)


def _rebuilt_modal_damping(model, small):
    """``small`` with its damping rebuilt the way the case built the original's, when that is modal
    damping: D = M Φ diag(2 ζ_j ω_j) Φᵀ M over the model's own eigenmodes, ζ_j by mode index taken
    from the original (Φᵀ D Φ diagonal). Modal damping depends on the basis — a coarser reduction
    puts different high system modes, with different 2 ζ ω_j, under the quasi-static response —
    and the coarser model of (4) is meant to be the case's reduction with fewer modes."""
    import scipy.linalg

    from sarfe.hbm.model import LinearModel

    dense = (lambda A: A.toarray() if hasattr(A, "toarray") else np.asarray(A, dtype=float))
    if model.damping is None:
        return small
    M, K, D = dense(model.mass), dense(model.stiffness), dense(model.damping)
    w2, phi = scipy.linalg.eigh(0.5 * (K + K.T), 0.5 * (M + M.T))
    modal = phi.T @ D @ phi
    off = modal - np.diag(np.diag(modal))
    if np.abs(off).max(initial=0.0) > 1e-6 * np.abs(np.diag(modal)).max(initial=1e-300):
        return small                                   # not modal damping: keep the projection
    omega = np.sqrt(np.clip(w2, 1e-300, None))
    zeta = np.diag(modal) / (2 * omega)
    Ms, Ks = dense(small.mass), dense(small.stiffness)
    w2s, phis = scipy.linalg.eigh(0.5 * (Ks + Ks.T), 0.5 * (Ms + Ms.T))
    weighted = Ms @ phis
    Ds = (weighted * (2.0 * zeta[:len(w2s)] * np.sqrt(np.clip(w2s, 0.0, None)))) @ weighted.T
    return LinearModel(small.mass, 0.5 * (Ds + Ds.T), small.stiffness)


_COARSER = {}     # coarser model per (model, contacts, excitation, modes): built once per run


def coarser_model(model, contacts, excitation, modal_dofs, residual_dofs=(), fraction=0.2):
    """(T, coarser LinearModel, its ContactSet, modes left out) of (4), cached: the coarser model
    does not depend on the point, only its start does."""
    from dataclasses import replace

    import scipy.sparse as sp

    from sarfe.hbm.model import LinearModel

    modal_dofs = np.asarray(modal_dofs, dtype=int)
    residual_dofs = np.asarray(residual_dofs, dtype=int)
    key = (id(model), id(contacts), id(excitation), modal_dofs.tobytes(), residual_dofs.tobytes(),
           float(fraction))
    hit = _COARSER.get(key)
    if hit is not None and hit[0] is model and hit[1] is contacts and hit[2] is excitation:
        return hit[3]
    removed = modal_dofs[-max(1, int(len(modal_dofs) * fraction)):]
    T = coarser_basis(model, excitation, int(modal_dofs.min()), removed, residual_dofs)

    def project(A):
        if A is None:
            return None
        return T.T @ (A @ T if hasattr(A, "toarray") else np.asarray(A) @ T)

    small = LinearModel(project(model.mass), project(model.damping), project(model.stiffness))
    small = _rebuilt_modal_damping(model, small)
    small_contacts = replace(contacts, gap_map=sp.csr_matrix(contacts.gap_map @ T))
    value = (T, small, small_contacts, len(removed))
    if len(_COARSER) >= 4:
        _COARSER.clear()
    _COARSER[key] = (model, contacts, excitation, value)
    return value


def modal_truncation_change(solution, model, contacts, excitation, modal_dofs, residual_dofs=(),
                            erp_map=None, erp_areas=None, options=None, ref_amplitude=None,
                            steps=None, fraction=0.2):
    r"""(4): change of the solution on the coarser model T (:func:`coarser_basis`, the top fifth of
    the modes ``modal_dofs`` — at least one — left out), re-solved (1) from the solution projected
    on it → (relative amplitude change, |ERP level change| [dB], modes left out) or None when the
    re-solve fails. modal_dofs: the fixed-interface modal coordinates in increasing frequency;
    residual_dofs: the residual modes (rebuilt for the coarser model).
    """
    from types import SimpleNamespace

    T, small, small_contacts, removed = coarser_model(model, contacts, excitation, modal_dofs,
                                                      residual_dofs, fraction)
    U = np.asarray(solution.displacement, dtype=float)
    # start: the M-orthogonal projection of ũ on span T
    M = model.mass.toarray() if hasattr(model.mass, "toarray") else np.asarray(model.mass)
    start = np.linalg.solve(small.mass, ((U @ M) @ T).T).T
    H, N = int(solution.harmonics), int(solution.samples_per_period)
    F_small = resize_harmonics(np.asarray(excitation) @ T, H)
    U_small = newton_step(small, small_contacts, F_small, start, float(solution.omega), H, N,
                          options, steps)
    if U_small is None:
        U_small = newton_correction(small, small_contacts, F_small,
                                    SimpleNamespace(displacement=start, omega=solution.omega,
                                                    harmonics=H), H, N, options)
    if U_small is None:
        return None
    rel, db = _change(contacts, U, U_small @ T.T, float(solution.omega), erp_map, erp_areas,
                      ref_amplitude)
    return rel, abs(db), removed


def harmonics_richardson(harmonics: int, extended: int) -> float:
    """(3) with p = 1 for a change H → H'': 1 / (1 − H/H''), at least RICHARDSON (a doubling's) —
    an extension past the doubling reaches resonant harmonics, below which the decay is not yet
    the asymptotic one, so it does not lower the factor."""
    if extended <= harmonics:
        return RICHARDSON
    return float(max(RICHARDSON, 1.0 / (1.0 - harmonics / extended)))


def mode_richardson(modes, coarser_modes, decay=1.0) -> float:
    """1 / ((m/m')^p − 1): the kept model's error from the change m' → m modes (4), for an error
    ∝ m^{−p} (p = ``decay``). With plate-like modal density (ω_j ∝ j, constant per Hz, the slowest
    among shells) both the quasi-static share of the omitted modes without residual modes, Σ_{j>m}
    (ω/ω_j)², and the basis dependence of modal damping (2 ζ ω/ω_h on the quasi-static response,
    ω_h ∝ m the highest system mode) decay like m^{−1}: p = 1 is the slowest decay; for m' = 4m/5
    the factor is then 4, for m' = 19m/20 it is 19."""
    return float(1.0 / ((modes / max(coarser_modes, 1)) ** decay - 1.0))


def mode_decay(modes, coarser, changes) -> float:
    """p of (5), fitted from the changes d₁, d₂ of two probes m₁' > m₂' (fewer modes left out
    first): d_i = e (r_i^p − 1), r_i = m/m_i', so d₂/d₁ = (r₂^p − 1)/(r₁^p − 1), increasing in p;
    solved by Brent's method and kept in MODE_DECAY (a ratio at or below its p = 1 value — the
    changes not decaying, or not monotone — gives p = 1, the slowest decay of
    :func:`mode_richardson`)."""
    from scipy.optimize import brentq

    (m1, m2), (d1, d2) = coarser, changes
    if not (m1 > m2 and d1 > 0 and np.isfinite(d2)):
        return MODE_DECAY[0]
    r1, r2 = modes / m1, modes / m2
    lo, hi = MODE_DECAY
    mismatch = (lambda p: (r2 ** p - 1.0) / (r1 ** p - 1.0) - d2 / d1)
    if mismatch(lo) >= 0.0:
        return lo
    if mismatch(hi) <= 0.0:
        return hi
    return float(brentq(mismatch, lo, hi, xtol=1e-13))


def modal_extrapolation(modes, coarser, changes) -> tuple[float, float]:
    """(5): the kept model's modal-truncation error from the changes d_i of the probes with m_i'
    modes (fewer modes left out first) → (error, fitted p): d / (r^p − 1) of the largest probe
    (the last), p = :func:`mode_decay`. With p = 1 (changes that do not decay) that is the single
    top-fifth probe × 4; a steeper decay lowers the factor to 1/(1.25^2.5 − 1) = 1.34."""
    p = mode_decay(modes, coarser, changes) if len(changes) == 2 else MODE_DECAY[0]
    return float(changes[-1] * mode_richardson(modes, coarser[-1], p)), float(p)


@dataclass(frozen=True)
class ModalEstimate:
    """(5) of one solution: amplitude_rel, erp_db [dB] (NaN when no probe converged), notes."""

    amplitude_rel: float
    erp_db: float
    notes: tuple = ()


def modal_truncation_estimate(solution, model, contacts, excitation, modal_dofs, residual_dofs=(),
                              erp_map=None, erp_areas=None, options=None, ref_amplitude=None,
                              steps=None) -> ModalEstimate:
    """(4)–(5): the probes of MODE_PROBES (:func:`modal_truncation_change`) extrapolated with the
    fitted decay (:func:`modal_extrapolation`)."""
    residual_dofs = () if residual_dofs is None else residual_dofs
    kept = len(modal_dofs)
    probes = [modal_truncation_change(solution, model, contacts, excitation, modal_dofs,
                                      residual_dofs, erp_map, erp_areas, options, ref_amplitude,
                                      steps, fraction)
              for fraction in MODE_PROBES]
    probes = [p for p in probes if p is not None]
    if not probes:
        return ModalEstimate(float("nan"), float("nan"), notes=("modal estimate: singular Jacobian",))
    coarser = [kept - p[2] for p in probes]
    m_rel, _ = modal_extrapolation(kept, coarser, [p[0] for p in probes])
    m_db, _ = modal_extrapolation(kept, coarser, [p[1] for p in probes])
    notes = (("modal estimate: one probe did not converge (p = 1 on the other)",)
             if len(probes) < len(MODE_PROBES) else ())
    return ModalEstimate(m_rel, m_db, notes)


def samples_for(harmonics: int, samples_per_period: int) -> int:
    """N kept at least 4H+1 (no aliasing of quadratic terms), as a power of two when N was one."""
    need = 4 * harmonics + 1
    N = int(samples_per_period)
    while N < need:
        N *= 2
    return N


def estimate_errors(solution, model, contacts, excitation, *, erp_map=None, erp_areas=None,
                    modal_dofs=None, residual_dofs=None, harmonics_extension=None, aliasing=True,
                    truncation=True, options=None, steps=None) -> ErrorEstimate:
    """Error estimates of a converged :class:`HarmonicSolution` (module docstring).

    model, contacts, excitation f̃_e (2H+1, n) [N]: the problem the solution solves.
    erp_map (n_s, n), erp_areas (n_s,) [m²]: radiating normal displacements (default all DOFs).
    modal_dofs: indices of the fixed-interface modal coordinates, sorted by frequency (None for a
    model without modal truncation); residual_dofs: the Craig–Bampton residual modes (4).
    harmonics_extension: H' (default :func:`extended_harmonics`).
    """
    clock = time.perf_counter()
    H, N = int(solution.harmonics), int(solution.samples_per_period)
    U = np.asarray(solution.displacement, dtype=float)
    omega = float(solution.omega)
    notes = []
    R = np.asarray(solution.contact_displacement, dtype=float)
    lam = np.asarray(solution.contact_force, dtype=float)
    disp_tail = spectral_tail(R) if R.size else spectral_tail(U)
    force_tail = spectral_tail(lam) if lam.size else 0.0
    a_ref = np.max(_first_harmonic_amplitude(contacts, U), initial=0.0) or None

    nan = float("nan")
    h_rel = h_db = a_rel = a_db = nan
    H_ext = int(harmonics_extension or extended_harmonics(H))
    if truncation:
        U_new = newton_step(model, contacts, resize_harmonics(excitation, H_ext),
                            resize_harmonics(U, H_ext), omega, H_ext, samples_for(H_ext, N),
                            options, steps)
        for robust in (False, True):  # a large raise changed the active set: climb ×1.5 a step
            if U_new is None:
                U_new = newton_correction(model, contacts, excitation, solution, H_ext,
                                          samples_for(H_ext, N), options, robust)
                notes.append("truncation estimate: H raised in steps (one Newton solve at H' did "
                             "not converge)" + (", by the engine's solver" if robust else ""))
        if U_new is None:   # unknown, not small
            h_rel = h_db = float("inf")
            notes.append("truncation estimate: no re-solve with more harmonics converged")
        else:
            if (U_new.shape[0] - 1) // 2 < H_ext:
                notes.append(f"truncation estimate: H raised to {(U_new.shape[0] - 1) // 2} of "
                             f"{H_ext} (the next raise did not converge)")
                H_ext = (U_new.shape[0] - 1) // 2
            h_rel, h_db = _change(contacts, resize_harmonics(U, H_ext), U_new, omega, erp_map,
                                  erp_areas, a_ref)
    if aliasing:
        U_new = newton_step(model, contacts, resize_harmonics(excitation, H), U, omega, H, 2 * N,
                            options, steps)
        if U_new is None:   # (the cheap climb at the same H would repeat the step above exactly)
            U_new = newton_correction(model, contacts, excitation, solution, H, 2 * N, options,
                                      robust=True)
        if U_new is None:   # unknown, not small
            a_rel = a_db = float("inf")
            notes.append("aliasing estimate: no re-solve with 2N converged")
        else:
            a_rel, a_db = _change(contacts, U, U_new, omega, erp_map, erp_areas, a_ref)

    m_rel = m_db = nan
    if truncation and modal_dofs is not None and len(modal_dofs):
        modal = modal_truncation_estimate(solution, model, contacts, excitation, modal_dofs,
                                          residual_dofs, erp_map, erp_areas, options, a_ref, steps)
        m_rel, m_db = modal.amplitude_rel, modal.erp_db
        notes.extend(modal.notes)
    factor = harmonics_richardson(H, H_ext)
    parts_rel = [f * x for f, x in ((factor, h_rel), (RICHARDSON, a_rel)) if not np.isnan(x)]
    parts_db = [f * abs(x) for f, x in ((factor, h_db), (RICHARDSON, a_db)) if not np.isnan(x)]
    parts_rel += [m_rel] if np.isfinite(m_rel) else []
    parts_db += [m_db] if np.isfinite(m_db) else []
    active = lam.size and np.max(np.abs(np.asarray(solution.contact_force_time)), initial=0.0) > 0
    if active:     # resolution floor: below it the parts cannot be told from round-off
        parts_rel.append(AMPLITUDE_FLOOR)
        parts_db.append(ERP_FLOOR_DB)
    if not getattr(solution, "converged", True):
        notes.append(f"solution not converged: {getattr(solution, 'reason', '')}")
    return ErrorEstimate(
        harmonics=H, samples_per_period=N, extended_harmonics=H_ext,
        harmonics_rel=h_rel, harmonics_db=h_db, aliasing_rel=a_rel, aliasing_db=a_db,
        modal_rel=m_rel, modal_db=m_db, displacement_tail=disp_tail, force_tail=force_tail,
        amplitude_rel=float(sum(parts_rel)) if parts_rel else nan,
        erp_db=float(sum(parts_db)) if parts_db else nan,
        seconds=time.perf_counter() - clock, notes=tuple(notes))


@dataclass(frozen=True)
class EstimateProblem:
    """What :func:`problem_error_estimate` needs of a case's point, as plain arrays: the problem
    (model, contacts, excitation f̃_e (2H_e+1, n) [N]), the radiating normal displacements
    (erp_map (n_s, n), erp_areas (n_s,) [m²]; None: all DOFs, unit areas), the Craig–Bampton
    fixed-interface modal coordinates (sorted by frequency) and residual modes (None for models
    without modal truncation) and the model's highest natural frequency [Hz] (None: unknown)."""

    model: object
    contacts: object
    excitation: np.ndarray
    erp_map: object = None
    erp_areas: object = None
    modal_dofs: object = None
    residual_dofs: object = None
    highest_mode_hz: float | None = None


def problem_error_estimate(solution, problem: EstimateProblem, options=None) -> ErrorEstimate:
    """:func:`estimate_errors` of a case's point with H' reaching past the model's highest mode
    (:func:`reach_harmonics`); on a Craig–Bampton model (modal_dofs given) the highest kept mode is
    recorded as ``basis_top_hz``."""
    from dataclasses import replace

    H_ext = reach_harmonics(int(solution.harmonics), float(solution.omega), problem.highest_mode_hz)
    estimate = estimate_errors(solution, problem.model, problem.contacts, problem.excitation,
                               erp_map=problem.erp_map, erp_areas=problem.erp_areas,
                               modal_dofs=problem.modal_dofs, residual_dofs=problem.residual_dofs,
                               harmonics_extension=H_ext, options=options)
    top = problem.highest_mode_hz
    if problem.modal_dofs is not None and len(problem.modal_dofs) and top is not None \
            and np.isfinite(top):
        estimate = replace(estimate, basis_top_hz=float(top))
    return estimate


def basis_limited_extension(estimate: dict, frequency_hz: float) -> bool:
    """True when the harmonics change of ``estimate`` (an :meth:`ErrorEstimate.as_dict`) reached
    past the top of its Craig–Bampton basis, H' f > basis_top_hz: the harmonics between the top
    and H' f are answered by the residual vectors, and the change includes the reduced model's
    own error there. Measured on P1 at 5 mm (benchmarks/results/accuracy_5mm.md): with the top at
    H f_max (cutoff_margin 1.0) the first harmonics above it overshoot the truth's contact
    amplitude 1.3–1.8× (the residual vectors' Ritz frequencies start just above the cutoff) and
    the change H → 2H is 1.4–1.6× the true one; with the top at 1.25 H f_max, 0.8–1.5×."""
    top = estimate.get("basis_top_hz", float("nan"))
    top = float("nan") if top is None else float(top)
    return bool(np.isfinite(top) and int(estimate["extended_harmonics"]) * frequency_hz > top)


def highest_natural_frequency_hz(model):
    """Highest undamped natural frequency [Hz] of a small dense model (None above 2000 DOFs)."""
    import scipy.linalg

    if model.dof_count > 2000:
        return None
    dense = (lambda A: A.toarray() if hasattr(A, "toarray") else np.asarray(A, dtype=float))
    values = scipy.linalg.eigh(dense(model.stiffness), dense(model.mass), eigvals_only=True)
    return float(np.sqrt(max(values.max(initial=0.0), 0.0)) / (2 * np.pi))


def _at_least(N, need):
    while N < need:
        N *= 2
    return int(N)


__all__ = ["RICHARDSON", "PRESETS", "AccuracyTarget", "parse_accuracy", "ErrorEstimate",
           "resize_harmonics", "spectral_tail", "harmonic_energy", "newton_correction",
           "extended_harmonics", "reach_harmonics", "samples_for", "estimate_errors", "EstimateProblem",
           "problem_error_estimate", "basis_limited_extension", "highest_natural_frequency_hz"]
