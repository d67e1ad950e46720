r"""Onset factor: by what factor s the excitation may grow before a contact starts to rattle or
slip, from the linear response of the structure with its contacts at their static state (no
nonlinear solve).

The linear rest state is the one of the pipeline's linear baseline (preloaded / closed pairs as
their law's springs and dashpots, friction pairs that carry a static normal force stuck as k_t,
open pairs removed; :func:`rest_response`). In it a contact's relative displacements are

    w(θ; s) = w0 + s w_dyn(θ),    q(θ; s) = q0 + s q_dyn(θ)           [m],   θ = ωt,

with the static part w0, q0 (row 0: the static load f̃_e,0 and the contacts' preloads — not
scaled) and the periodic part w_dyn = Σ_{k≥1} w_kc cos kθ + w_ks sin kθ of the excitation's orders
k ≥ 1 (× s). The linearized normal force of a closed contact (law linearization at u = 0: spring k,
dashpot c, preload λ_0, :func:`sarfe.hbm.laws.linearization`) is N(θ; s) = N0 + s N_dyn(θ) with

    N0 = λ_0 + k w0,      N_dyn = k w_dyn + c ẇ_dyn,      ẇ_dyn = ω ∂w_dyn/∂θ

(N0 = λ_0 of an open contact or one without a normal row: its constant normal load). s* is the
smallest s > 0 at which some θ leaves the rest state, the smallest of

* closing (open at rest, g > w0):       w0 + s w_dyn(θ) = g         → s(θ) = (g − w0)/w_dyn(θ),
* separation (closed at rest), the first of the law's kink w = g, s(θ) = (w0 − g)/(−w_dyn(θ)), and
  of the linearized force reaching the law's force at the kink λ_g = λ_n(w = g, ẇ = 0) (0, or the
  constant load N0 of a squeak law):  N0 − λ_g + s N_dyn(θ) = 0 → s(θ) = (N0 − λ_g)/(−N_dyn(θ));
  for a dashpot law it comes before the kink;
* slip (a tangent element stuck at rest, N0 > 0): with λ_t = k_t q (the stuck spring, the gauge
  of :mod:`sarfe.hbm.laws.jenkins`), a = k_t q0, b(θ) = k_t q_dyn(θ) (1 or 2 directions),

      |a + s b| = μ (N0 + s N_dyn)   ⇔   α s² + 2β s + γ = 0,
      α = |b|² − μ² N_dyn²,   β = a·b − μ² N0 N_dyn,   γ = |a|² − μ² N0² < 0 (stuck at rest),

  whose smallest positive root is s(θ) = −γ / (β + √(β² − αγ)) (where β + √(β² − αγ) > 0; it lies
  before the normal force vanishes, where |a + s b| ≥ 0 = μN). A pair whose stuck static force
  k_t q0 would exceed μN0 slid while it was preloaded: a = μN0 ê (:func:`rest_response`), γ = 0
  and s* = 0 — it slips at the first cycle (the squeak rig's pad).

That slip is the first one from the rest state (slider where it was assembled). It may be a single
one: the slider moves and the contact sticks again (shakedown), as long as the disks of stuck
sliders D(θ) = {w : |q(θ) − w| ≤ μN(θ)/k_t} still have a common point. Steady stick–slip — what
the periodic solution shows (the slider gauge of :mod:`sarfe.hbm.laws.jenkins`: the common point
nearest to the rest position) and what squeaks period after period — starts when they have none.
In one tangent direction that is, with the static parts cancelling,

    s_steady = 2μN0 / ( max_θ(λ_d − μN_dyn) + max_θ(−λ_d − μN_dyn) ),   λ_d = b (one direction),

(= μN0 / (½ ptp λ_d) under a constant normal force: the swing of the tangential force, not its
peak, must reach the slip limit). In two directions the same is taken along tangent-plane
directions e (λ_d → e·b) and minimized over e: exact for a constant normal force and an orbit
symmetric about its centre (one harmonic: the disks meet iff the orbit's minimal enclosing circle
fits, radius = half its longest chord), otherwise an upper bound (pairwise meeting disks are
necessary, not sufficient) — on the squeak rig (2-D, N varying, 50/100/150 Hz) equal to 1e-12 to
the bisection with the periodic solution's own test of whether the disks meet
(:func:`sarfe.hbm.laws.jenkins_march.stick_projection`). s_steady ≥ the first-slip factor; they
agree when the static tangential force is 0, N is constant and the orbit is symmetric (the
lumped seal).

Limit of the steady factor: at the onset of steady slip the disks meet in one point x*, so the
static tangential force is −x*, not the rest state's; where the contact couples its static
tangential and normal loads (an inclined or bending pad), N0 moves with it. The rest state keeps
its N0: on the squeak rig at 150 Hz (N0 2.05 N there, 2.02 N in the periodic solution) the steady
factor is 2.6 % above the level at which the periodic solution starts to slip.

For one harmonic the closing factor is the textbook s* = (g − w0)/|ŵ1|, |ŵ1| = √(w_1c² + w_1s²).
Each s(θ) is evaluated on N samples of the period (vectorized over samples × contacts) and its
minimum refined by the parabola through the smallest sample and its two neighbours (error
O((2π/N)⁴) of a smooth minimum). s* < 1: the contact is already active at the given excitation;
s* = 0: active at rest (statically closed, separated or slipping); s* = ∞: never (no motion
towards the event). In decibels, 20 log10 s* (:attr:`OnsetFactors.level_db`).

Companion of the linear risk index :mod:`sarfe.erp.risk` (d = g − t − |ŵ1| < 0): closed form, the
same linear response, but a factor on the excitation and every law's event (closing, separation,
slip).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sarfe.hbm import laws
from sarfe.hbm.harmonics import derivative_matrix, time_samples
from sarfe.hbm.solve import linearized_guess, linearized_rows, make_problem

__all__ = ["OnsetFactors", "RestResponse", "rest_contacts", "rest_rows", "rest_response",
           "onset_factors",
           "excitation_onset", "ONSET_SAMPLES"]

ONSET_SAMPLES = 512     # samples of the period on which s(θ) is minimized (then refined)
DIRECTIONS = 90         # tangent-plane directions over [0, π) of the 2-D steady-slip factor

CLOSING, SEPARATION, SLIP = "closing", "separation", "slip"


@dataclass(frozen=True)
class OnsetFactors:
    """Per contact (n_c,): onset factor s* [-] of the excitation (module docstring), the event that
    sets it (``mechanism``: 'closing' | 'separation' | 'slip' | '' where s* = ∞), its phase θ* =
    ωt [rad] in the period, and the factor of each kind of event (∞ where it cannot happen):
    ``normal_factor`` (closing or separation), ``slip_factor`` (first slip from the rest state),
    ``steady_slip_factor`` (steady stick–slip, after the slider's shakedown)."""

    factor: np.ndarray
    mechanism: np.ndarray
    phase_rad: np.ndarray
    normal_factor: np.ndarray
    slip_factor: np.ndarray
    steady_slip_factor: np.ndarray

    @property
    def steady_factor(self) -> np.ndarray:
        """min(normal, steady slip) (n_c,): the factor at which the periodic response stops being
        the linear one (what a sweep of the nonlinear solution in excitation level finds)."""
        return np.minimum(self.normal_factor, self.steady_slip_factor)

    @property
    def level_db(self) -> np.ndarray:
        """20 log10 s* [dB]: the excitation margin (negative: already active at s = 1)."""
        with np.errstate(divide="ignore"):
            return 20.0 * np.log10(self.factor)


def rest_contacts(contacts, slid=None):
    """The contact set whose law linearization (:func:`sarfe.hbm.laws.linearization`) is the rest
    state — the ONE definition shared by the onset factor and the pipeline's linear baseline
    (:func:`rest_rows`): every normal row closed at u = 0 keeps its law's spring and dashpot (a
    preloaded pair; open pairs carry nothing), and the tangent spring k_t stays only where the
    contact carries a static normal force (λ_n(0) > 0: stuck) and not where it ``slid`` (n_c,)
    bool. For :func:`sarfe.hbm.solve.linearized_guess` and :func:`rest_rows` only (k_t = 0 is not
    a valid Jenkins element for a solve)."""
    normal, _ = laws.linearization(contacts)
    keep = normal.preload > 0
    if slid is not None:
        keep &= ~slid
    table = dict(contacts.parameters)
    if "tangential_stiffness" in table:
        table["tangential_stiffness"] = np.where(keep, table["tangential_stiffness"], 0.0)
    return replace(contacts, parameters=table)


def rest_rows(contacts):
    """(spring [N/m], dashpot [N s/m], preload [N]) per row of G in the rest state
    (:func:`rest_contacts`, :func:`sarfe.hbm.solve.linearized_rows`): the matrices
    K + Gᵀ diag(spring) G and D + Gᵀ diag(dashpot) G of the linear rest structure."""
    return linearized_rows(rest_contacts(contacts))


@dataclass(frozen=True)
class RestResponse:
    """The linear response in the rest state (:func:`rest_response`): displacement ũ (2H+1, n) [m]
    (row 0 the static state, rows k ≥ 1 the response to the excitation's orders k ≥ 1);
    tangential_force λ_t,0 (n_c, 2) [N] the static tangential force of each friction pair (0
    without a stuck tangent element); slid (n_c,) bool: the pair slid while it was preloaded
    (|λ_t,0| = μ N0)."""

    displacement: np.ndarray
    tangential_force: np.ndarray
    slid: np.ndarray


STATIC_ITERATIONS = 50


def _linear_solve(model, contacts, excitation, omega):
    F = np.asarray(excitation, dtype=float)
    H = (F.shape[0] - 1) // 2
    return linearized_guess(make_problem(model, contacts, F, H, 4 * H + 1), float(omega))


def rest_response(model, contacts, excitation, omega) -> RestResponse:
    """The linear structure with the contacts at their static state under f̃_e (2H+1, n) [N] at
    ω [rad/s]: per order k (the preloads λ_0 at k = 0),

        (K + Gᵀ diag(k_r) G − (kω)² M + i kω (D + Gᵀ diag(c_r) G)) Û_k = F̂_k  (− Gᵀ λ_0 at k = 0),

    k_r, c_r the rest springs and dashpots of the rows (:func:`sarfe.hbm.solve.linearized_guess`
    on the rest linearization; zeros where the system is singular).

    Static friction limit: a stuck pair whose static tangential force k_t q0 exceeds μ N0 (the
    preload pushes the pair sideways, e.g. an inclined or bending contact) slid while it was
    preloaded and carries μ N0 along that force (the state the periodic solution's slider gauge
    reaches at small excitation); the static state is solved again with those pairs' tangent
    springs replaced by their forces, N0 updated, until no further pair slides and N0 settles
    (a few passes; 2-D: the direction of the first stuck trial force is kept). Its dynamic
    response stays the stuck spring's (small motions about the slid position stick)."""
    F = np.asarray(excitation, dtype=float)
    U = _linear_solve(model, rest_contacts(contacts), F, omega)
    normal, spring_t = laws.linearization(contacts)
    G = contacts.gap_map
    closed = (contacts.normal_row >= 0) & normal.closed
    rows_t = contacts.tangent_rows
    present = rows_t >= 0
    friction = (spring_t > 0) & present[:, 0] & (normal.preload > 0)
    mu = contacts.friction_coefficient

    def static_forces(u0):          # N0, the stuck trial force k_t q0, the limit μ N0
        r0 = np.asarray(G @ u0)
        N0 = normal.preload + np.where(closed, normal.spring * r0[np.maximum(
            contacts.normal_row, 0)], 0.0)
        trial = spring_t[:, None] * np.where(present, r0[np.maximum(rows_t, 0)], 0.0)
        return N0, trial, mu * np.maximum(N0, 0.0)

    slid = np.zeros(contacts.count, bool)
    direction = np.zeros((contacts.count, 2))
    static = np.zeros((3, F.shape[1]))
    u0 = U[0]
    N0, trial, limit = static_forces(u0)
    for _ in range(STATIC_ITERATIONS):
        new = friction & ~slid & (np.linalg.norm(trial, axis=1) > limit * (1 + 1e-12))
        if not np.any(new) and (not np.any(slid) or np.allclose(N0, previous, rtol=1e-12,
                                                                   atol=0.0)):
            break
        direction[new] = trial[new] / np.linalg.norm(trial[new], axis=1)[:, None]
        slid |= new
        previous = N0
        force = limit[:, None] * direction                             # (n_c, 2) on the rows
        on = present & slid[:, None]
        load = np.zeros(contacts.row_count)
        np.add.at(load, rows_t[on], force[on])
        static[0] = F[0] - np.asarray(G.T @ load)
        u0 = _linear_solve(model, rest_contacts(contacts, slid), static, omega)[0]
        N0, trial, limit = static_forces(u0)
    tangential = np.where(slid[:, None], limit[:, None] * direction, trial) * friction[:, None]
    displacement = U.copy()
    displacement[0] = u0
    return RestResponse(displacement, tangential, slid)


def excitation_onset(model, contacts, excitation, omega,
                     samples_per_period=ONSET_SAMPLES) -> OnsetFactors:
    """:func:`onset_factors` of the rest response (:func:`rest_response`) to f̃_e (2H+1, n) [N]."""
    rest = rest_response(model, contacts, excitation, omega)
    R = np.asarray(contacts.gap_map @ rest.displacement.T).T
    return onset_factors(contacts, R, omega, samples_per_period, rest.tangential_force)


def _smallest(s, samples):
    """(min over θ, θ at the min) of s(θ) (N, n) sampled at θ_j = 2πj/N, the minimum refined by
    the parabola through the smallest sample and its neighbours where all three are finite."""
    j = np.argmin(s, axis=0)
    cols = np.arange(s.shape[1])
    s0 = s[j, cols]
    left, right = s[(j - 1) % samples, cols], s[(j + 1) % samples, cols]
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        curvature = left - 2.0 * s0 + right
        ok = np.isfinite(left) & np.isfinite(right) & np.isfinite(s0) & (curvature > 0)
        shift = np.where(ok, 0.5 * (left - right) / np.where(ok, curvature, 1.0), 0.0)
        shift = np.clip(shift, -0.5, 0.5)
        value = np.where(ok, s0 - 0.25 * (left - right) * shift, s0)
    return value, 2.0 * np.pi * (j + shift) / samples


def _largest(x, samples):
    """max over θ of x(θ) (N, n), refined like :func:`_smallest`."""
    return -_smallest(-x, samples)[0]


def _steady_slip(a_dyn, normal_dyn, static_limit, two_d, samples, directions=DIRECTIONS):
    """Steady stick–slip factor (module docstring) of tangential force swings λ_d = ``a_dyn``
    (N, n, 2) [N] with μN_dyn = ``normal_dyn`` (N, n) and μN0 = ``static_limit`` (n,): along
    e = (1, 0) (one direction); where ``two_d``, the smallest over the directions e (refined by a
    parabola)."""
    angles = np.pi * np.arange(directions) / directions if np.any(two_d) else np.zeros(0)
    e = np.column_stack([[1.0, 0.0], np.stack([np.cos(angles), np.sin(angles)])])  # (2, 1 + m)
    x = a_dyn @ e                                              # (N, n, 1 + m): all directions
    N, n, m = x.shape
    dyn = normal_dyn[:, :, None]
    swing = (_largest((x - dyn).reshape(N, n * m), samples)
             + _largest((-x - dyn).reshape(N, n * m), samples)).reshape(n, m)
    ratio = _ratio(2.0 * static_limit[:, None], swing)          # (n, 1 + m)
    result = ratio[:, 0]
    if angles.size:
        result = np.where(two_d, _smallest(ratio[:, 1:].T, directions)[0], result)
    return result


def _ratio(distance, approach):
    """s(θ) = distance / approach where both are > 0, 0 where distance ≤ 0 (already there), ∞
    where the motion does not approach; broadcast (N, n)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(approach > 0, distance / np.where(approach > 0, approach, 1.0), np.inf)
    return np.where(distance <= 0, 0.0, s)


def _kink_force(contacts):
    """λ_g (n_c,) [N]: each law's normal force at the kink w = g, ẇ = 0 (0 for a penalty law,
    the constant load N0 of a squeak law)."""
    out = np.zeros(contacts.count)
    for contact_law, idx, p in laws.groups(contacts):
        gap = contacts.gap[idx]
        out[idx] = contact_law.normal(p, gap, gap[None], np.zeros((1, idx.size))).force[0]
    return out


def onset_factors(contacts, contact_displacement, omega, samples_per_period=ONSET_SAMPLES,
                  tangential_force=None) -> OnsetFactors:
    """Onset factor of every contact (module docstring) from the contact-row harmonics r̃ = G ũ
    (2H+1, n_rows) [m] of the linear rest response (:func:`rest_response`): row 0 the static part
    (held), rows k ≥ 1 the part that scales with the excitation. ω [rad/s] (dashpot laws);
    samples_per_period N of the minimization; tangential_force: the static λ_t,0 (n_c, 2) [N]
    (:class:`RestResponse`; default k_t q0, every friction pair stuck where it was assembled).
    Vectorized over samples × contacts."""
    R = np.asarray(contact_displacement, dtype=float)
    H, N = (R.shape[0] - 1) // 2, int(samples_per_period)
    n_c = contacts.count
    dynamic = R.copy()
    dynamic[0] = 0.0
    r = time_samples(dynamic, N)                                        # (N, n_rows)
    rate = float(omega) * time_samples(derivative_matrix(H) @ dynamic, N)
    static = R[0]
    normal, tangent_spring = laws.linearization(contacts)
    has_n = contacts.normal_row >= 0
    row = np.maximum(contacts.normal_row, 0)
    w0 = np.where(has_n, static[row], 0.0)
    w = np.where(has_n, r[:, row], 0.0)
    wdot = np.where(has_n, rate[:, row], 0.0)
    g = contacts.gap
    closed = has_n & normal.closed
    N0 = normal.preload + np.where(closed, normal.spring * w0, 0.0)
    N_dyn = np.where(closed, normal.spring * w + normal.dashpot * wdot, 0.0)   # (N, n_c)

    no_event = np.full((N, n_c), np.inf)
    closing = np.where(has_n & ~closed, _ratio(g - w0, w), no_event)
    kink = np.where(closed, _ratio(w0 - g, -w), no_event)
    force = np.where(closed, _ratio(N0 - _kink_force(contacts), -N_dyn), no_event)

    # slip of a stuck tangent element: |a + s b| = μ (N0 + s N_dyn), smallest positive root
    rows_t = contacts.tangent_rows
    present = rows_t >= 0
    stuck = (tangent_spring > 0) & present[:, 0] & (normal.preload > 0)
    k_t = tangent_spring[:, None]
    a = k_t * np.where(present, static[np.maximum(rows_t, 0)], 0.0) if tangential_force is None \
        else np.asarray(tangential_force, dtype=float)                      # (n_c, 2) [N]
    b = k_t * np.where(present, r[:, np.maximum(rows_t, 0)], 0.0)               # (N, n_c, 2)
    mu = contacts.friction_coefficient
    alpha = np.einsum("jcd,jcd->jc", b, b) - (mu * N_dyn) ** 2
    beta = np.einsum("cd,jcd->jc", a, b) - mu**2 * N0 * N_dyn
    gamma = np.einsum("cd,cd->c", a, a) - (mu * N0) ** 2
    with np.errstate(invalid="ignore", divide="ignore"):
        root = np.sqrt(np.maximum(beta**2 - alpha * gamma, 0.0))
        real = (beta**2 - alpha * gamma >= 0) & (beta + root > 0)
        slip = np.where(real, -gamma / np.where(real, beta + root, 1.0), np.inf)
    slip = np.where(gamma >= -1e-9 * (mu * N0) ** 2, 0.0, slip)     # at the limit at rest
    slip = np.where(stuck, slip, no_event)
    steady = np.where(stuck, _steady_slip(b, mu * N_dyn, mu * N0, present[:, 1], N), np.inf)

    kinds = (CLOSING, SEPARATION, SEPARATION, SLIP)
    minima = [_smallest(s, N) for s in (closing, kink, force, slip)]
    values = np.stack([m[0] for m in minima])                          # (4, n_c)
    phases = np.stack([m[1] for m in minima])
    first = np.argmin(values, axis=0)
    cols = np.arange(n_c)
    factor = values[first, cols]
    mechanism = np.where(np.isfinite(factor), np.asarray(kinds, dtype=object)[first], "")
    return OnsetFactors(factor=factor, mechanism=mechanism,
                        phase_rad=np.mod(phases[first, cols], 2.0 * np.pi),
                        normal_factor=values[:3].min(axis=0), slip_factor=values[3],
                        steady_slip_factor=steady)
