r"""A curved contact partner: the normal approach and the contact normal follow the slide.

A friction contact (normal relative displacement w closing the gap g, tangential relative
displacements q = (q₁, q₂) in the contact's tangent plane) whose two surfaces are curved with
relative principal radii R₁, R₂ along the tangent directions (convex > 0). Two bodies of radii
R_a, R_b (each > 0 convex, < 0 concave) touching at a point: after a relative slide s (rigid, no
rotation) their nearest distance is g + s²/(2(R_a + R_b)), and the common normal at the new
contact point has turned by s/(R_a + R_b) — so R = R_a + R_b (a sharp pad, R_a → 0, on a curved
partner: R = R_b; a sphere on a plane, R_b → ∞: no effect). With the curvatures κ_i = 1/R_i
(``partner_curvature_1``, ``_2`` [1/m]; 0 = flat) the penetration is, to second order in q,

    δ = w − g − ½ (κ₁ q₁² + κ₂ q₂²),

so a convex partner (κ > 0: a pad sliding over a rib, a ball or a cylinder) opens the gap as it
slides and a concave one (κ < 0: a pad in a groove or a cup) closes it. A normal penalty
λ_n = k_n max(0, δ) + N0 then varies at twice the sliding frequency: q = a cos ωt gives
λ_n = k_n (δ₀ − κa²/4 − (κa²/4) cos 2ωt) while closed (δ₀ = w − g at q = 0). The normal force
acts along the turned normal, so its components on the contact's fixed axes are the derivatives
of the penalty energy V(δ):

    λ_w = ∂V/∂w = λ_n,      λ_q,i = ∂V/∂q_i = −κ_i q_i λ_n     (first order in the turn κ q),

a conservative (symmetric) coupling: a negative tangential stiffness −κλ_n on a convex partner
(the pad slides off the crest), a restoring one on a concave partner. The Jenkins element
(:mod:`.jenkins`) acts on q with slip limit μ λ_n(δ); the friction force stays in the fixed
tangent plane (its component λ_t κ q on the normal axis is neglected: it is small against the
modelled k_n κ q²/2 when the slide amplitude exceeds 2 μ δ₀).

The geometry is the contact's (``partner_radius_m`` in the case file: one radius for both
tangent directions, or two [R₁, R₂] along tangent directions 1, 2 with null = flat); the solver
stages (AFT, time integration, Hill stability) reach it through :func:`curvatures` and the
functions below, so they all see the same law.
"""
from __future__ import annotations

import numpy as np

from sarfe.hbm.laws.contract import LawInputError, Parameter

PARAMETERS = tuple(
    Parameter(f"partner_curvature_{i}", None, "1/m",
              f"relative curvature 1/R_{i} of the contact partners along tangent direction {i} "
              "(convex > 0, concave < 0, 0 flat; case: partner_radius_m)", default=0.0,
              normal_part=True)
    for i in (1, 2))

CASE_KEY = "partner_radius_m"
CASE_KEYS = {CASE_KEY: {"oneOf": [
    {"type": "number"},
    {"type": "array", "minItems": 2, "maxItems": 2, "items": {"type": ["number", "null"]}}]}}


def prepare(contact, resolve=None) -> dict:
    """{partner_curvature_1, partner_curvature_2} [1/m] of a contact's ``partner_radius_m``
    (absent: flat, 0). Raises LawInputError naming the key."""
    radius = contact.get(CASE_KEY)
    if radius is None:
        return {}
    if "tangential_dofs" in contact and "normal_dof" not in contact:
        raise LawInputError(CASE_KEY, "needs a normal DOF (the curvature changes the normal "
                                      "approach; without one the normal load is constant)")
    radii = [radius, radius] if not isinstance(radius, (list, tuple)) else list(radius)
    out = {}
    for i, r in enumerate(radii, start=1):
        if r is not None and (not np.isfinite(r) or r == 0.0):
            raise LawInputError(CASE_KEY, f"radius must be a non-zero finite number (convex > 0, "
                                          f"concave < 0) or null (flat), got {r!r}")
        out[f"partner_curvature_{i}"] = 0.0 if r is None else 1.0 / float(r)
    return out


def curvatures(p):
    """κ (n, 2) [1/m] of a law group's parameters, or None when every partner is flat (then
    nothing changes: the flat law, bit for bit)."""
    if "partner_curvature_1" not in p:
        return None
    kappa = np.stack([p["partner_curvature_1"], p["partner_curvature_2"]], axis=-1)
    return kappa if np.any(kappa != 0.0) else None


def contact_curvatures(contacts) -> np.ndarray:
    """κ (n_c, 2) [1/m] of every contact of a :class:`sarfe.hbm.contacts.ContactSet` (0: flat)."""
    return np.stack([np.asarray(contacts.partner_curvature_1, dtype=float),
                     np.asarray(contacts.partner_curvature_2, dtype=float)], axis=-1)


def penetration_shift(kappa, q):
    """½ Σ_i κ_i q_i² (...) [m]: w − g − shift is the penetration. q (..., 2), κ broadcast."""
    return 0.5 * np.einsum("...i,...i->...", kappa, q * q)


def effective_normal(kappa, w, q):
    """The normal displacement the flat law sees, w − ½ Σ κ_i q_i² (..., n) [m]."""
    return w - penetration_shift(kappa, q)


def coupling(kappa, q, force, stiffness):
    r"""The pointwise terms of a curved partner at samples (..., n): q (..., n, 2) [m], λ_n
    ``force`` and ∂λ_n/∂δ ``stiffness`` (..., n) of the flat law at the penetration δ.

    Returns (λ_q (..., n, 2) [N] = −κ q λ_n, the normal force's tangential components;
    ∂λ_n/∂q (..., n, 2) [N/m] = −k κ q, also ∂λ_q/∂w (the coupling is symmetric);
    ∂λ_q/∂q (..., n, 2, 2) [N/m] = −diag(κ) λ_n + k (κ∘q)(κ∘q)ᵀ)."""
    kq = kappa * q
    tangential = -kq * force[..., None]
    slope = -kq * stiffness[..., None]
    hessian = kq[..., :, None] * kq[..., None, :] * stiffness[..., None, None]
    hessian = hessian - (kappa * force[..., None])[..., None] * np.eye(2)
    return tangential, slope, hessian


def friction_force(kappa, q, tangential_force, normal_force):
    """The friction part λ_t = λ_q + κ q λ_n (..., n, 2) [N] of the tangent-row forces
    ``tangential_force`` (..., n, 2) of contacts with normal force λ_n (..., n): the row forces
    less the normal force's tangential components (:func:`coupling`)."""
    return tangential_force + kappa * q * normal_force[..., None]


def friction_rows(contacts, r, force):
    """The contact-row forces ``force`` (N, n_rows) [N] with the tangent rows of every curved
    contact replaced by its friction part (:func:`friction_force`; the outputs' friction force,
    slider and slip work); r (N, n_rows) [m] the contact displacements at the same samples.
    ``contacts``: a :class:`sarfe.hbm.contacts.ContactSet`. Unchanged (the same array) when no
    contact is curved."""
    kappa = contact_curvatures(contacts)
    normal_row = np.asarray(contacts.normal_row)
    curved = np.flatnonzero(np.any(kappa != 0.0, axis=1) & (normal_row >= 0))
    if not curved.size:
        return force
    rows = np.asarray(contacts.tangent_rows)[curved]
    on = rows >= 0
    safe = np.maximum(rows, 0)
    q = np.where(on[None], r[:, safe], 0.0)
    friction = friction_force(kappa[curved], q, np.where(on[None], force[:, safe], 0.0),
                              force[:, normal_row[curved]])
    out = np.array(force, dtype=float, copy=True)
    out[:, rows[on]] = friction[:, on]
    return out


def local_jacobian(kappa, q, force, stiffness, d_tq=None, d_tn=None):
    r"""∂λ/∂(w, q₁, q₂) (n, 3, 3) at one instant of n contacts with a curved partner: the normal
    row, the tangential rows (friction λ_t plus −κ q λ_n). The friction's ∂λ_t/∂q ``d_tq``
    (n, 2, 2) and ∂λ_t/∂λ_n ``d_tn`` (n, 2) (the slip limit μ λ_n) of :func:`.jenkins.step`;
    λ_n depends on (w, q) through δ: dλ_n = k (dw − κ q dq)."""
    _, slope, hessian = coupling(kappa, q, force, stiffness)
    n = force.shape[0]
    J = np.zeros((n, 3, 3))
    J[:, 0, 0] = stiffness
    J[:, 0, 1:] = slope
    J[:, 1:, 0] = slope
    J[:, 1:, 1:] = hessian
    if d_tq is not None:
        J[:, 1:, 1:] += d_tq + d_tn[:, :, None] * slope[:, None, :]
        J[:, 1:, 0] += d_tn * stiffness[:, None]
    return J


__all__ = ["PARAMETERS", "CASE_KEY", "CASE_KEYS", "prepare", "curvatures", "contact_curvatures",
           "penetration_shift",
           "effective_normal", "coupling", "friction_force", "friction_rows", "local_jacobian"]
