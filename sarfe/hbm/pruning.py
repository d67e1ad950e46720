r"""Contact screening and pruning (engine): contacts that never switch are solved linearly.
The pipeline uses it (:mod:`sarfe.pipeline.solve.pruned_points`).

Contact screening (a cheap linear pass). At every ω of a grid over the sweep, the response of the
linear model with each contact linearized at u = 0 (what :func:`sarfe.hbm.solve.linearized_guess`
solves: each law's linearization — preloaded contacts as their springs with their preload, open ones
absent, tangent elements stuck)
gives the relative normal motion w(θ) of every contact — read on the contact rows only
(:func:`contact_row_responses`: the model's modal compliance G Z_k⁻¹ Gᵀ with the linearized contacts
as a Woodbury update, no solve of model size per ω). With the gap g and a margin m ∈ (0, 1):

- ``open``   (g > 0):  max_{ω,θ} w ≤ (1 − m) g      — never closes: λ ≡ 0, drop the contact;
- ``closed`` (g < 0, a law that is ``linear_when_closed``, e.g. rattle): min_{ω,θ} (w − g) ≥
  m (w₀ − g), w₀ the static (mean) closure — the compression never drops below m × its static
  value, never opens: λ = k w + p (the law's linearization: spring k, preload p) is exact,
  add k gᵣᵀ gᵣ to K and −p gᵣᵀ to the static load f̃_e,0 (gᵣ: its row of G);
- otherwise ``nonlinear`` (kept), with the reason. A law's ``prune_open`` may keep a contact that
  never closes (friction under a normal load N0 > 0: its slider state is history dependent even
  when it never slips).

Because the other contacts' nonlinear response can drive a screened contact, :func:`check_pruning`
re-checks every decision on the nonlinear solution (w of the dropped contacts is still G u); a
violated decision means: solve again with the full set (:func:`solve_frequency_pruned` does that
for one ω; :mod:`sarfe.pipeline.solve.pruned_points` for the points or the sweep of a case in
``sarfe solve``).
:func:`restore_solution` re-expresses a pruned solution with all contacts, keeping the solver's own
forces of the kept ones.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from sarfe.hbm.dynamic_stiffness import apply_dynamic_stiffness, from_complex, to_complex
from sarfe.hbm.harmonics import time_samples
from sarfe.hbm.laws import linearization, pruning_rules
from sarfe.hbm.modal import cached_modal_basis, real_product
from sarfe.hbm.model import make_linear_model
from sarfe.hbm.solution import HarmonicSolution
from sarfe.hbm.solve import linearized_rows, solve_frequency
from sarfe.hbm.time_integration import linear_harmonic_response

OPEN, CLOSED, NONLINEAR = "open", "closed", "nonlinear"


@dataclass(frozen=True)
class ContactDecision:
    """How one contact is modelled. clearance: the screened quantity relative to |g| —
    open: (g − max w)/g, closed: min(w − g)/(w₀ − g) (≥ margin for the decision), nan when not
    screened."""

    index: int
    name: str
    kind: str
    decision: str
    clearance: float
    reason: str


@dataclass(frozen=True)
class PrunedProblem:
    """The problem with screened contacts removed: model (closed contacts' springs added), contacts
    (kept ones only), excitation (preloads moved to the static row), and the bookkeeping."""

    model: object
    contacts: object
    excitation: np.ndarray
    kept: np.ndarray            # indices of the kept contacts in the full set
    decisions: tuple


def linearized_stiffness(model, contacts):
    r"""(K_lin, f_pre) of the contacts linearized at u = 0, as :func:`sarfe.hbm.solve.linearized_guess`:
    K_lin = K + Gᵀ diag(k) G with k the laws' springs on the normal rows of pairs closed at u = 0
    and k_t on the stuck tangents; f_pre = −Gᵀ p [N], p the laws' preloads on the normal rows
    (:func:`sarfe.hbm.solve.linearized_rows`). Dense (n, n) [N/m] if the model is dense, else
    sparse CSC."""

    k, _, preload = linearized_rows(contacts)
    G = sp.csr_matrix(contacts.gap_map)
    added = G.T @ sp.diags(k) @ G
    K = model.stiffness
    K = (sp.csc_matrix(K) + added).tocsc() if sp.issparse(K) else np.asarray(K) + added.toarray()
    return K, -np.asarray(G.T @ preload).ravel()


def linearized_damping(model, contacts):
    """D + Gᵀ diag(c) G with the laws' dashpots c of the contacts closed at u = 0 (D itself when
    every law is rate independent) [N s/m]."""

    c = linearized_rows(contacts)[1]
    D = model.damping
    if not np.any(c):
        return D
    G = sp.csr_matrix(contacts.gap_map)
    added = G.T @ sp.diags(c) @ G
    return (sp.csc_matrix(D) + added).tocsc() if sp.issparse(D) else np.asarray(D) + added.toarray()


def _solve(A, b):

    if sp.issparse(A):
        return spla.spsolve(sp.csc_matrix(A), b)
    try:
        return np.linalg.solve(A, b)
    except np.linalg.LinAlgError:          # singular (a DOF held only by contacts): least squares
        return np.linalg.lstsq(A, b, rcond=None)[0]


def linear_responses(model, contacts, excitation, omegas):
    r"""ũ (2H+1, n) [m] of the linearized model at each ω of ``omegas`` [rad/s] (a generator):
    K_lin u₀ = f̃_e,0 + f_pre and per harmonic k, (K_lin − (kω)² M + i kω D) Û_k = F_kc − i F_ks,
    u_kc = Re Û_k, u_ks = −Im Û_k — what :func:`sarfe.hbm.solve.linearized_guess` solves as one
    real system, here harmonic by harmonic."""
    F = np.asarray(excitation, dtype=float)
    K, f_pre = linearized_stiffness(model, contacts)
    M, D = model.mass, linearized_damping(model, contacts)
    if not sp.issparse(K):
        M, D = (A.toarray() if sp.issparse(A) else np.asarray(A) for A in (M, D))
    static = np.real(_solve(K, F[0] + f_pre))
    for omega in np.atleast_1d(omegas):
        U = np.zeros(F.shape)
        U[0] = static
        for k in range(1, (F.shape[0] - 1) // 2 + 1):
            rhs = F[2 * k - 1] - 1j * F[2 * k]
            if np.any(rhs):
                w = k * float(omega)
                Uk = _solve(K - w * w * M + 1j * w * D, rhs)
                U[2 * k - 1], U[2 * k] = Uk.real, -Uk.imag
        yield U


# bound on the (frequencies × rows × modes) and (frequencies × rows × rows) complex arrays of one
# block of frequencies
_BLOCK_ENTRIES = 4_000_000
# the screen takes the modal path from this many (ω, order) solves on: the modal basis of the door
# trim's reduced model (613 DOFs) costs as much as ≈ 6 complex solves of it (80 ms vs 13 ms each)
MODAL_SCREEN_MIN_SOLVES = 8


def modal_row_responses(basis, contacts, excitation, omegas):
    r"""(r̃ (n_ω, 2h+1, n_rows) [m], bad (n_ω,) bool): the linearized model's response at the rows
    of G from the modal basis of the model (no solve of model size per ω; h: the excitation's
    highest order), ``bad`` where some Z_k(ω) is singular. See :func:`contact_row_responses`."""

    c = contacts
    springs, dashpots, preload = linearized_rows(c)
    Gd = sp.csr_matrix(c.gap_map).toarray()
    n_rows = Gd.shape[0]
    forces = to_complex(np.asarray(excitation, dtype=float))       # (h+1, n): f_k = f_kc − i f_ks
    h = forces.shape[0] - 1
    gap_modes, _, static_compliance = basis.gap_projection(Gd)     # GV, ·, G K⁻¹ Gᵀ
    static_forced, modal_forced = basis.load_projection(forces)    # K⁻¹ f_k, Vᵀ f_k
    row_static = static_forced @ Gd.T                               # G K⁻¹ f_k (h+1, n_rows)
    row_modal = modal_forced[:, None, :] * gap_modes[None]          # (Vᵀf_k)_j (GV)_rj
    active = np.flatnonzero((springs != 0) | (dashpots != 0))
    omegas = np.asarray(omegas, dtype=float)
    R = np.zeros((omegas.size, h + 1, n_rows), dtype=complex)
    # static order: K r₀ … (I + C₀ diag(k)) r₀ = G K⁻¹ f₀ − C₀ p, λ₀ = k r₀ + p (same at every ω)
    R[:, 0] = _spring_update(static_compliance[None], (row_static[0] - static_compliance
                                                       @ preload)[None], springs[None], active)[0]
    bad = np.zeros(omegas.size, bool)
    if h == 0:
        return R, bad
    k = np.arange(1, h + 1)
    block = max(1, _BLOCK_ENTRIES // max(1, h * n_rows * max(n_rows, gap_modes.shape[1])))
    for start in range(0, omegas.size, block):
        w = omegas[start:start + block]
        kw = (w[:, None] * k[None, :]).ravel()                      # (b h,): a_kj depends on kω
        if basis.singular(kw, 1.0):                                 # an undamped resonance
            bad[start:start + block] = [basis.singular(x, 1.0) for x in kw.reshape(w.size, h)]
        q = basis.dynamic_receptance(kw, 1.0)                       # (b h, n_modes)
        # C_k = G K⁻¹ Gᵀ + (GV) diag(q_k) (GV)ᵀ,  G y_k = G K⁻¹ f_k + (GV)(q_k ⊙ Vᵀ f_k)
        C = static_compliance[None] + real_product(
            (gap_modes[None] * q[:, None, :]).reshape(-1, q.shape[1]),
            gap_modes.T).reshape(kw.size, n_rows, n_rows)
        loaded = (row_static[None, 1:] + np.einsum(
            "bkj,krj->bkr", q.reshape(w.size, h, -1), row_modal[1:])).reshape(kw.size, n_rows)
        s = springs[None] + 1j * kw[:, None] * dashpots[None]       # λ_k = (k + i kω c) r_k
        R[start:start + block, 1:] = _spring_update(C, loaded, s, active).reshape(w.size, h, n_rows)
    return np.moveaxis(from_complex(np.moveaxis(R, 1, 0)), 0, 1), bad


def _spring_update(C, b, s, active):
    r"""r (p, n_rows) of (I + C diag(s)) r = b for p stacked systems (C (p, n_rows, n_rows), b and
    s (p, n_rows)): only the rows a with s ≠ 0 couple, (I + C_aa diag(s_a)) r_a = b_a, then
    r = b − C_:a (s_a ⊙ r_a) (Woodbury: the springs and dashpots of the linearized contacts added
    to the model's compliance). Non-finite where a system is singular."""
    if not active.size:
        return np.array(b, dtype=np.result_type(C, b, s))
    sa = s[:, active]
    A = np.eye(active.size) + C[:, active[:, None], active[None, :]] * sa[:, None, :]
    try:
        ra = np.linalg.solve(A, b[:, active, None])[..., 0]
    except np.linalg.LinAlgError:          # one of them is singular: those get nan
        ra = np.stack([_solve_or_nan(a, x) for a, x in zip(A, b[:, active])])
    return b - np.einsum("pra,pa->pr", C[:, :, active], sa * ra)


def _solve_or_nan(A, b):
    try:
        return np.linalg.solve(A, b)
    except np.linalg.LinAlgError:
        return np.full(b.shape, np.nan, dtype=np.result_type(A, b))


def contact_row_responses(model, contacts, excitation, omegas, modal=True) -> np.ndarray:
    r"""r̃ = G ũ (n_ω, 2H+1, n_rows) [m] of the linearized model (:func:`linear_responses`) at each
    ω of ``omegas`` [rad/s], at the rows of G only.

    When the model has a modal basis (:func:`sarfe.hbm.modal.cached_modal_basis`: dense, e.g.
    Craig–Bampton, K positive definite, D diagonal in the undamped modes) the linearized contacts
    are a spring/dashpot update of the model's compliance at the contact rows, per order k

        C_k = G Z_k⁻¹ Gᵀ = G K⁻¹ Gᵀ + (GV) diag(q_k) (GV)ᵀ,  ŷ_k = G Z_k⁻¹ f_k,
        (I + C_k diag(k_s + i kω c)) r̂_k = ŷ_k,   (I + C₀ diag(k_s)) r̂₀ = ŷ₀ − C₀ p,

    (k_s, c, p the laws' springs, dashpots and preloads on the rows: :func:`sarfe.hbm.solve.
    linearized_rows`), so a frequency costs O(H n_rows² n_modes), vectorized over ω, and no solve of
    model size — the same equations as :func:`linear_responses` (Woodbury identity), not an
    approximation. Other models (sparse, non-modal damping, singular K) and any ω at which a Z_k is
    singular: :func:`linear_responses` there; so are fewer than MODAL_SCREEN_MIN_SOLVES (ω, order)
    pairs (a few listed frequencies: a handful of solves costs less than the basis, and the model's
    cache is left as the points find it), and ``modal`` False (the direct solves: a reference).
    """

    F = np.asarray(excitation, dtype=float)
    omegas = np.atleast_1d(np.asarray(omegas, dtype=float))
    G = contacts.gap_map
    basis = None
    if modal and omegas.size * ((F.shape[0] - 1) // 2) >= MODAL_SCREEN_MIN_SOLVES:
        # from the model's second request on its basis is computed once and cached on the model
        # (:func:`sarfe.hbm.modal.cached_modal_basis`): the sweep that follows reuses it
        basis = cached_modal_basis(model) or cached_modal_basis(model)
    if basis is None:
        return np.stack([np.asarray(G @ U.T).T
                         for U in linear_responses(model, contacts, F, omegas)])
    R, bad = modal_row_responses(basis, contacts, F, omegas)
    bad |= ~np.all(np.isfinite(R), axis=(1, 2))
    if np.any(bad):
        R[bad] = np.stack([np.asarray(G @ U.T).T
                           for U in linear_responses(model, contacts, F, omegas[bad])])
    return R


def screen_contacts(model, contacts, excitation, omegas, margin=0.5, samples=64,
                    modal=True) -> tuple:
    """Decisions (one :class:`ContactDecision` per contact) from the linear pass over ``omegas``.

    excitation f̃_e (2H+1, n) [N]; omegas [rad/s] — include the resonances in the band (a grid of a
    few hundred points, or the grid plus the linear natural frequencies); margin m (module docstring).
    The pass reads the contact rows only (:func:`contact_row_responses`; ``modal`` False: its
    direct solves of model size).
    """

    F = np.asarray(excitation, dtype=float)
    # the linear response has only the harmonics of the excitation: screen with those (exact)
    loaded = np.flatnonzero(np.any(F[1:] != 0, axis=1))
    highest = (int(loaded[-1]) + 2) // 2 if loaded.size else 1
    F = F[:2 * max(highest, 1) + 1]
    c = contacts
    has = c.normal_row >= 0
    normal = np.where(has, c.normal_row, 0)
    R = contact_row_responses(model, c, F, omegas, modal)[:, :, normal]   # (n_ω, 2h+1, n_c)
    w = time_samples(np.moveaxis(R, 0, 1), samples)                  # (samples, n_ω, n_c)
    w_max = np.where(has, w.max(axis=(0, 1)), -np.inf)
    w_min = np.where(has, w.min(axis=(0, 1)), np.inf)
    w_mean = np.where(has, R[-1, 0], 0.0)                            # static: same at every ω
    may_open, may_close = pruning_rules(c)
    decisions = []
    for i in range(c.count):
        name = c.names[i] if i < len(c.names) else f"contact_{i}"
        kind, g = str(c.kind[i]), float(c.gap[i])
        nan = float("nan")
        if not has[i]:
            decisions.append(ContactDecision(i, name, kind, NONLINEAR, nan,
                                             "no normal row (constant normal load): kept"))
            continue
        if not may_open[i]:
            decisions.append(ContactDecision(i, name, kind, NONLINEAR, nan,
                                             f"{kind} law keeps it (history under a normal load)"))
            continue
        if g > 0:
            clearance = (g - w_max[i]) / g
            if clearance >= margin:
                decisions.append(ContactDecision(
                    i, name, kind, OPEN, float(clearance),
                    f"never closes: max w = {w_max[i]:.3g} m ≤ (1 − {margin:g}) × gap {g:.3g} m"))
            else:
                decisions.append(ContactDecision(
                    i, name, kind, NONLINEAR, float(clearance),
                    f"closes or comes within {margin:g} × gap (max w = {w_max[i]:.3g} m, gap {g:.3g} m)"))
        elif g < 0 and may_close[i]:
            static = w_mean[i] - g
            clearance = (w_min[i] - g) / static if static > 0 else -np.inf
            if clearance >= margin:
                decisions.append(ContactDecision(
                    i, name, kind, CLOSED, float(clearance),
                    f"never opens: min (w − g) = {w_min[i] - g:.3g} m ≥ {margin:g} × static "
                    f"compression {static:.3g} m"))
            else:
                decisions.append(ContactDecision(
                    i, name, kind, NONLINEAR, float(clearance),
                    f"opens or comes within {margin:g} × static compression (min (w − g) = "
                    f"{w_min[i] - g:.3g} m, static {static:.3g} m)"))
        else:
            decisions.append(ContactDecision(i, name, kind, NONLINEAR, 0.0,
                                             "touching (gap 0), or preloaded and not linear "
                                             "while closed: kept"))
    return tuple(decisions)


def subset_contacts(contacts, indices):
    """ContactSet with only the contacts ``indices`` (their rows of G re-numbered)."""
    idx = np.asarray(indices, dtype=int)
    c = contacts
    rows = kept_rows(c, idx)
    new = {int(r): j for j, r in enumerate(rows)}
    remap = np.vectorize(lambda r: new.get(int(r), -1), otypes=[int])
    normal = remap(c.normal_row[idx]) if idx.size else np.zeros(0, int)
    tangent = remap(c.tangent_rows[idx]).reshape(-1, 2) if idx.size else np.zeros((0, 2), int)
    G = c.gap_map[rows] if rows.size else sp.csr_matrix((0, c.gap_map.shape[1]))
    return c.subset(idx, G, normal, tangent)


def prune_contacts(model, contacts, excitation, decisions) -> PrunedProblem:
    """Apply decisions: drop ``open`` contacts, turn ``closed`` contacts into their law's
    linearization (springs).

    Closed: λ = k w + p, w = gᵣ u → K += k gᵣᵀ gᵣ and f̃_e,0 −= p gᵣᵀ (exact while closed; for the
    penalty law k = k_n, p = −k_n g).
    """

    F = np.asarray(excitation, dtype=float).copy()
    K = model.stiffness
    closed = np.array([d.index for d in decisions if d.decision == CLOSED], dtype=int)
    if closed.size:
        G = sp.csr_matrix(contacts.gap_map[contacts.normal_row[closed]])      # rows gᵣ
        lin = linearization(contacts)[0]
        k, preload = lin.spring[closed], lin.preload[closed]
        add = G.T @ sp.diags(k) @ G
        F[0] -= np.asarray(G.T @ preload).ravel()
        K = (sp.csr_matrix(K) + add).tocsr() if sp.issparse(K) else np.asarray(K) + add.toarray()
    kept = np.array([d.index for d in decisions if d.decision == NONLINEAR], dtype=int)
    pruned_model = make_linear_model(model.mass, model.damping, K) if closed.size else model
    return PrunedProblem(pruned_model, subset_contacts(contacts, kept), F, kept, tuple(decisions))


def check_pruning(contacts, decisions, displacement, samples=256) -> list:
    """Decisions violated by a solution ũ (2H+1, n): [(name, what happened)] (empty = all hold).

    w(θ) = gᵣ u(θ) of every screened contact at ``samples`` points of the period (a multiple of
    the AFT samples N checks every sample the nonlinear solver saw, and more): ``open`` holds while
    max w ≤ g, ``closed`` while min w ≥ g.
    """

    screened = [d for d in decisions if d.decision != NONLINEAR]
    if not screened:
        return []
    index = np.array([d.index for d in screened], dtype=int)
    U = np.asarray(displacement, dtype=float)
    R = np.asarray(contacts.gap_map[contacts.normal_row[index]] @ U.T).T    # (2H+1, n_screened)
    w = time_samples(R, samples)                                             # (samples, n_screened)
    excess = w.max(axis=0) - contacts.gap[index]       # > 0: an "open" contact closes
    deficit = w.min(axis=0) - contacts.gap[index]      # < 0: a "closed" contact opens
    violated = []
    for j, d in enumerate(screened):
        if d.decision == OPEN and excess[j] > 0:
            violated.append((d.name, f"screened open but closes (max w − g = {excess[j]:.3g} m)"))
        if d.decision == CLOSED and deficit[j] < 0:
            violated.append((d.name, f"screened closed but opens (min w − g = {deficit[j]:.3g} m)"))
    return violated


def kept_rows(contacts, kept) -> np.ndarray:
    """Rows of G (full set) that :func:`subset_contacts` keeps for the contacts ``kept``, in the
    order of the subset's rows."""
    idx = np.asarray(kept, dtype=int)
    rows = np.concatenate([contacts.normal_row[idx], contacts.tangent_rows[idx].ravel()])
    return np.unique(rows[rows >= 0])


def restore_solution(solution, model, contacts, excitation, decisions):
    r"""A HarmonicSolution of the pruned problem re-expressed with the full contact set.

    Kept contacts: the solver's own forces, force samples and states (a friction contact's stuck
    offset depends on the slider history, so it is not re-evaluated). ``closed`` contacts: their
    law's linearization λ = k w + p (k_n (w − g) for the penalty law), state 1; ``open``: λ = 0,
    state 0. Residual ‖S ũ + Gᵀλ̃ − f̃_e‖ / ‖f̃_e‖ of the
    full equations (on the solved harmonic rows when the solution used a harmonic subset).
    """


    U = np.asarray(solution.displacement, dtype=float)
    F = np.asarray(excitation, dtype=float)
    N = int(solution.samples_per_period)
    R = np.asarray(contacts.gap_map @ U.T).T                     # (2H+1, n_rows)
    kept = np.array([d.index for d in decisions if d.decision == NONLINEAR], dtype=int)
    closed = np.array([d.index for d in decisions if d.decision == CLOSED], dtype=int)
    rows = kept_rows(contacts, kept)
    force = np.zeros_like(R)
    force_time = np.zeros((N, contacts.row_count))
    state = np.zeros((N, contacts.count), dtype=np.int8)
    if kept.size:
        force[:, rows] = solution.contact_force
        force_time[:, rows] = solution.contact_force_time
        state[:, kept] = solution.contact_state
    if closed.size:
        normal = contacts.normal_row[closed]
        lin = linearization(contacts)[0]
        k, preload = lin.spring[closed], lin.preload[closed]
        force[:, normal] = k * R[:, normal]
        force[0, normal] += preload
        force_time[:, normal] = k * time_samples(R[:, normal], N) + preload
        state[:, closed] = 1
    residual = apply_dynamic_stiffness(model, solution.omega, U) + \
        np.asarray(contacts.gap_map.T @ force.T).T - F
    orders = getattr(solution, "harmonic_orders", None)
    if orders is not None:
        residual = residual[[r for k in sorted(orders)
                             for r in ((0,) if k == 0 else (2 * k - 1, 2 * k))]]
    reference = np.linalg.norm(F) or 1.0
    return replace(solution, contact_displacement=R, contact_force=force,
                   contact_force_time=force_time, contact_state=state,
                   residual_norm=float(np.linalg.norm(residual) / reference))


def solve_frequency_pruned(model, contacts, excitation, omega, harmonics, samples_per_period,
                           decisions, initial=None, options=None):
    """solve_frequency on the pruned problem, checked; falls back to the full set on a violation.

    Returns (HarmonicSolution with all contacts, report dict {'kept', 'dropped', 'violations',
    'fallback'}).
    """

    pruned = prune_contacts(model, contacts, excitation, decisions)
    dropped = [d.name for d in decisions if d.decision != NONLINEAR]
    report = {"kept": [contacts.names[i] for i in pruned.kept], "dropped": dropped,
              "violations": [], "fallback": False}
    if pruned.contacts.count == 0:

        U = linear_harmonic_response(pruned.model, pruned.excitation, omega)
        solution = _linear_solution(U, omega, harmonics, samples_per_period)
    else:
        solution = solve_frequency(pruned.model, pruned.contacts, pruned.excitation, omega,
                                   harmonics, samples_per_period, initial=initial, options=options)
    report["violations"] = check_pruning(contacts, decisions, solution.displacement)
    if report["violations"]:
        report["fallback"] = True
        full = solve_frequency(model, contacts, excitation, omega, harmonics, samples_per_period,
                               initial=initial, options=options)
        if not full.converged:
            retry = solve_frequency(model, contacts, excitation, omega, harmonics,
                                    samples_per_period, initial=solution.displacement,
                                    options=options)
            full = retry if retry.converged else full
        return full, report
    return restore_solution(solution, model, contacts, excitation, decisions), report


def _linear_solution(U, omega, harmonics, samples_per_period):

    z = np.zeros((U.shape[0], 0))
    return HarmonicSolution(omega=float(omega), harmonics=int(harmonics),
                            samples_per_period=int(samples_per_period), displacement=U,
                            contact_displacement=z, contact_force=z,
                            contact_force_time=np.zeros((samples_per_period, 0)),
                            contact_state=np.zeros((samples_per_period, 0), np.int8),
                            converged=True, reason="linear (no nonlinear contact left)",
                            iterations=0, residual_norm=0.0, method="linear")


__all__ = ["OPEN", "CLOSED", "NONLINEAR", "ContactDecision", "PrunedProblem", "screen_contacts",
           "subset_contacts", "kept_rows", "prune_contacts", "check_pruning", "restore_solution",
           "linearized_stiffness", "linearized_damping", "linear_responses",
           "contact_row_responses", "modal_row_responses",
           "solve_frequency_pruned"]
