r"""Accuracy as an input: cheap a-posteriori error estimates of a harmonic-balance solution and an
adaptive choice of H (harmonics), N (AFT samples per period) and the fixed-interface mode count.

A solution ũ (2H+1, n) at ω solves R_{H,N}(ũ) = S(ω) ũ + f̃_nl^{(N)}(ũ) − f̃_e = 0. Embedded in a richer
discretization (H', N') it leaves a residual R_{H',N'}(ũ) ≠ 0; one Newton step

    δ = −J_{H',N'}(ũ)⁻¹ R_{H',N'}(ũ)                                             (1)

estimates the change of the solution when H → H' (harmonic truncation) or N → N' = 2N (AFT aliasing).
It costs one Jacobian factorization, i.e. one Newton iteration of the richer problem. The changes are
measured on the quantities users read:

- ``amplitude_rel``: max over contact rows of |Δ a₁| / max a₁, a₁ = first-harmonic amplitude of r = G u;
- ``erp_db``: 10 log₁₀(P(ũ+δ)/P(ũ)), P = Σ_k (kω)² Σ_s a_s |w_{s,k}|² (ERP ∝ normal velocity²,
  w = E ũ the radiating normal displacements, a_s their areas; all DOFs with unit areas when no E).

Cheaper still and model-free (no solve at all) are the spectral tails

    tail(X) = ‖X_{k > H − m}‖ / ‖X_{k ≥ 1}‖,  m = max(1, ⌊H/4⌋)                   (2)

of the contact displacements and forces (energy in the highest kept harmonics). For the modal
truncation of a Craig–Bampton model (coordinates [q_b, q_m], modes sorted by frequency) the
contribution of the highest kept modes (top fifth, at least one) to the same quantities is reported
as ``modal_rel`` / ``modal_db``: omitted modes are stiffer still, so their share is smaller.

``amplitude_rel`` and ``erp_db`` are SAFETY = 2 × the sum of the contributions: the one-step
estimate only sees harmonics up to H' and is first order at the contact kinks; on the shipped
lumped case it was 0.5–1× the true error before the factor (benchmarks/results/accuracy.md).

An ERP level error of ε_dB corresponds to a relative amplitude error 10^{ε_dB/20} − 1 (0.5 dB ≈ 5.9 %).
"""
from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np

SAFETY = 2.0

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
    N → 2N (1); modal_rel / modal_db: highest kept modes; displacement_tail / force_tail: (2).
    amplitude_rel, erp_db: SAFETY × the sum of the computed contributions (what :func:`choose_resolution`
    compares with the target). seconds: time spent estimating.
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


def _erp_proxy(U, omega, erp_map=None, erp_areas=None):
    """P = Σ_k (kω)² Σ_s a_s |w_{s,k}|² (proportional to the ERP of all harmonics)."""
    U = np.asarray(U, dtype=float)
    W = U if erp_map is None else np.asarray(U @ np.asarray(erp_map).T)
    areas = np.ones(W.shape[1]) if erp_areas is None else np.asarray(erp_areas, dtype=float)
    H = (W.shape[0] - 1) // 2
    k = np.repeat(np.arange(1, H + 1), 2)
    return float(((k[:, None] * omega) ** 2 * W[1:] ** 2 * areas).sum())


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
    p0 = _erp_proxy(U, omega, erp_map, erp_areas)
    p1 = _erp_proxy(U_new, omega, erp_map, erp_areas)
    if erp_map is not None:
        # a radiating surface that is silent compared with the structure (power ratio < 1e-24,
        # amplitude < 1e-12: round-off) has no meaningful level change
        whole = _erp_proxy(U, omega) * (np.sum(erp_areas) if erp_areas is not None else 1.0)
        if max(p0, p1) <= 1e-24 * whole:
            return rel, 0.0
    db = float(10 * np.log10(p1 / p0)) if p0 > 0 and p1 > 0 else (0.0 if p0 == p1 else float("inf"))
    return rel, db


def newton_correction(model, contacts, excitation, solution, harmonics, samples_per_period,
                      options=None):
    """(1): one Newton step δ of the (H', N') problem from the solution embedded in it → ũ + δ.

    excitation f̃_e (2H_e+1, n) [N] (resized to H'). Returns (2H'+1, n) [m] or None when the
    Jacobian is singular or the step is not finite.
    """
    from sarfe.hbm.newton import SingularJacobian, solve_linear
    from sarfe.hbm.residual import full_residual
    from sarfe.hbm.solve import make_problem

    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        F = resize_harmonics(excitation, harmonics)
        problem = make_problem(model, contacts, F, harmonics, samples_per_period, options)
        U = resize_harmonics(solution.displacement, harmonics)
        with np.errstate(all="ignore"):
            ev = full_residual(problem, U.ravel(), solution.omega, None, jacobian=True)
        if not np.all(np.isfinite(ev.residual)):
            return None
        try:
            step = solve_linear(ev.jacobian, -ev.residual)
        except SingularJacobian:
            return None
    U_new = U + step.reshape(U.shape)
    return U_new if np.all(np.isfinite(U_new)) else None


def extended_harmonics(harmonics: int) -> int:
    """H' used for the truncation estimate: H + max(2, ⌈H/2⌉)."""
    return int(harmonics + max(2, math.ceil(harmonics / 2)))


def samples_for(harmonics: int, samples_per_period: int) -> int:
    """N kept at least 4H+1 (no aliasing of quadratic terms), as a power of two when N was one."""
    need = 4 * harmonics + 1
    N = int(samples_per_period)
    while N < need:
        N *= 2
    return N


def estimate_errors(solution, model, contacts, excitation, *, erp_map=None, erp_areas=None,
                    modal_dofs=None, harmonics_extension=None, aliasing=True, truncation=True,
                    options=None) -> ErrorEstimate:
    """Error estimates of a converged :class:`HarmonicSolution` (module docstring).

    model, contacts, excitation f̃_e (2H+1, n) [N]: the problem the solution solves.
    erp_map (n_s, n), erp_areas (n_s,) [m²]: radiating normal displacements (default all DOFs).
    modal_dofs: indices of the fixed-interface modal coordinates, sorted by frequency (None for a
    model without modal truncation). harmonics_extension: H' (default :func:`extended_harmonics`).
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
        U_new = newton_correction(model, contacts, excitation, solution, H_ext,
                                  samples_for(H_ext, N), options)
        if U_new is None:
            notes.append("truncation estimate: singular Jacobian")
        else:
            h_rel, h_db = _change(contacts, resize_harmonics(U, H_ext), U_new, omega, erp_map,
                                  erp_areas, a_ref)
    if aliasing:
        U_new = newton_correction(model, contacts, excitation, solution, H, 2 * N, options)
        if U_new is None:
            notes.append("aliasing estimate: singular Jacobian")
        else:
            a_rel, a_db = _change(contacts, U, U_new, omega, erp_map, erp_areas, a_ref)

    m_rel = m_db = nan
    if modal_dofs is not None and len(modal_dofs):
        modal_dofs = np.asarray(modal_dofs, dtype=int)
        top = modal_dofs[-max(1, len(modal_dofs) // 5):]
        U_top = np.zeros_like(U)
        U_top[:, top] = U[:, top]
        m_rel, m_db = _change(contacts, U, U - U_top, omega, erp_map, erp_areas, a_ref)
        m_db = abs(m_db)
    parts_rel = [x for x in (h_rel, a_rel, m_rel) if np.isfinite(x)]
    parts_db = [abs(x) for x in (h_db, a_db, m_db) if np.isfinite(x)]
    if not getattr(solution, "converged", True):
        notes.append(f"solution not converged: {getattr(solution, 'reason', '')}")
    return ErrorEstimate(
        harmonics=H, samples_per_period=N, extended_harmonics=H_ext,
        harmonics_rel=h_rel, harmonics_db=h_db, aliasing_rel=a_rel, aliasing_db=a_db,
        modal_rel=m_rel, modal_db=m_db, displacement_tail=disp_tail, force_tail=force_tail,
        amplitude_rel=SAFETY * float(sum(parts_rel)) if parts_rel else nan,
        erp_db=SAFETY * float(sum(parts_db)) if parts_db else nan,
        seconds=time.perf_counter() - clock, notes=tuple(notes))


# ---------------------------------------------------------------------------- adaptive choice
@dataclass(frozen=True)
class Resolution:
    """Result of :func:`choose_resolution`: the final solution, its H, N, estimate and the history
    (one dict per round: H, N, converged, iterations, estimate, seconds); met: target reached."""

    solution: object
    harmonics: int
    samples_per_period: int
    estimate: ErrorEstimate
    met: bool
    reason: str
    history: list


def stage_error_estimate(solution, stage, nl) -> ErrorEstimate:
    """:func:`estimate_errors` of a case's point: the problem ``nl`` (sarfe.pipeline.nonlinear_model)
    on the linear ``stage``, its ERP map and areas, and for FE stages the modal coordinates (the
    reduced DOFs after the Craig–Bampton boundary DOFs) as the modal-truncation candidates."""
    modal = (np.arange(int(stage.info.get("boundary_dofs", 0)), stage.dof_count)
             if stage.kind == "fe" else None)
    return estimate_errors(solution, nl.model, nl.contacts, nl.excitation, erp_map=stage.erp_map,
                           erp_areas=stage.erp_areas, modal_dofs=modal)


def choose_resolution(target, model, contacts, excitation, omega, *, harmonics=3,
                      samples_per_period=64, max_harmonics=64, max_samples=8192, max_rounds=12,
                      erp_map=None, erp_areas=None, modal_dofs=None, options=None,
                      initial=None) -> Resolution:
    """Adaptive H, N at one ω [rad/s] until the estimates meet ``target`` (see :func:`parse_accuracy`).

    Loop: solve (warm-started from the previous round, cold with the engine's homotopy if that
    fails, and once more with 2N if it still fails); while the truncation estimate H → H' exceeds
    half the budget, H ← H' (N doubled to keep N/H ≥ its starting ratio and N ≥ 4H+1); else while
    the aliasing estimate N → 2N exceeds half the budget, N ← 2N. Stops at max_harmonics / max_samples / max_rounds (met=False, reason says why)
    or when a solve does not converge. excitation f̃_e (2H_e+1, n) [N] (any H_e; resized).
    """
    from sarfe.hbm.solve import solve_frequency

    import warnings

    target = parse_accuracy(target)
    H, N = int(harmonics), samples_for(int(harmonics), int(samples_per_period))
    ratio = max(4.0, N / H)                 # keep N/H ≥ the starting ratio as H grows
    history, previous = [], initial
    solution = estimate = None
    reason = f"round cap {max_rounds} reached"
    met = False
    retried = False
    for _ in range(max_rounds):
        clock = time.perf_counter()
        guess = None if previous is None else resize_harmonics(
            getattr(previous, "displacement", previous), H)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            F = resize_harmonics(excitation, H)
            solution = solve_frequency(model, contacts, F, omega, H, N, initial=guess,
                                       options=options)
            if not solution.converged and guess is not None:     # cold start (engine homotopy)
                cold = solve_frequency(model, contacts, F, omega, H, N, options=options)
                solution = cold if cold.converged else solution
        estimate = estimate_errors(solution, model, contacts, resize_harmonics(excitation, H),
                                   erp_map=erp_map, erp_areas=erp_areas, modal_dofs=modal_dofs,
                                   options=options)
        history.append({"harmonics": H, "samples_per_period": N,
                        "converged": bool(solution.converged), "iterations": int(solution.iterations),
                        "estimate": estimate.as_dict(), "seconds": time.perf_counter() - clock})
        if not solution.converged:
            if not retried and 2 * N <= max_samples:           # aliasing can stall Newton: once 2N
                retried, N = True, 2 * N
                continue
            reason = f"not converged at H={H}, N={N}: {solution.reason}"
            break
        previous = solution
        h_ok = target.met_by(SAFETY * _finite(estimate.harmonics_rel),
                             SAFETY * abs(_finite(estimate.harmonics_db)), 0.5)
        a_ok = target.met_by(SAFETY * _finite(estimate.aliasing_rel),
                             SAFETY * abs(_finite(estimate.aliasing_db)), 0.5)
        if h_ok and a_ok:
            met, reason = True, "target met"
            break
        if not h_ok:
            if H >= max_harmonics:
                reason = f"harmonics cap {max_harmonics} reached"
                break
            H = min(max_harmonics, estimate.extended_harmonics)
            N = min(max(max_samples, 4 * H + 1), _at_least(N, max(4 * H + 1, ratio * H)))
        else:
            if 2 * N > max_samples:
                reason = f"samples cap {max_samples} reached"
                break
            N *= 2
    return Resolution(solution, H if solution is None else int(solution.harmonics),
                      N if solution is None else int(solution.samples_per_period), estimate, met,
                      reason, history)


def _at_least(N, need):
    while N < need:
        N *= 2
    return int(N)


def _finite(x):
    return float(x) if np.isfinite(x) else 0.0


def suggest_mode_count(mode_frequencies_hz, max_frequency_hz, harmonics, target=None,
                       modal_rel=None, current=None) -> dict:
    """Fixed-interface mode count for an excited band up to H·f_max.

    Rule: keep the modes below c·H·f_max with c = 1.5 (fast), 2 (balanced), 3 (fine) — a mode at
    f_j answers a harmonic at f < f_j quasi-statically with relative error ≈ (f/f_j)², so c = 1.5
    leaves ≈ 45 %, c = 3 ≈ 11 % of the highest harmonic's (small) dynamic amplification. When a
    ``modal_rel`` estimate above the target is given, the current count is doubled.
    Returns {'mode_count', 'cutoff_hz', 'reason'}.
    """
    target = parse_accuracy(target or "balanced")
    budget = target.amplitude_budget()
    factor = 1.5 if budget >= 5e-2 else (2.0 if budget >= 1e-2 else 3.0)
    cutoff = factor * harmonics * max_frequency_hz
    f = np.asarray(mode_frequencies_hz, dtype=float)
    count = int(np.count_nonzero(f <= cutoff)) if f.size else 0
    reason = f"modes below {factor:g} H f_max = {cutoff:.0f} Hz"
    if modal_rel is not None and np.isfinite(modal_rel) and modal_rel > 0.5 * budget and current:
        count = max(count, 2 * int(current))
        reason += f"; modal estimate {modal_rel:.2g} above half the budget: doubled"
    return {"mode_count": count, "cutoff_hz": cutoff, "reason": reason}


__all__ = ["SAFETY", "PRESETS", "AccuracyTarget", "parse_accuracy", "ErrorEstimate", "Resolution",
           "resize_harmonics", "spectral_tail", "harmonic_energy", "newton_correction",
           "extended_harmonics", "samples_for", "estimate_errors", "stage_error_estimate", "choose_resolution",
           "suggest_mode_count"]
