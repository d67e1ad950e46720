r"""Damped impact: a penalty spring with a parallel dashpot while in contact, never pulling.

    λ_n = max(0, k_n (w − g) + c ẇ)   where w > g,    λ_n = 0 where w ≤ g

(Kelvin–Voigt contact with the no-pulling cut-off). The contact dissipates energy at each impact,
so its rebound is set by c: given directly (``damping_N_s_m``) or from a coefficient of
restitution e for the pair's effective mass m (``restitution``, ``effective_mass_kg``; left out,
the pipeline takes 1/m = g M⁻¹ gᵀ of the contact's normal row):

    c = 2 ζ(e) √(k_n m)

ζ(e) inverts the rebound of this law (not the textbook e = exp(−πζ/√(1−ζ²)), which ends the
contact at w = g): a mass m hitting the stop at v₀ follows m ẍ + c ẋ + k x = 0 (x = w − g) until
the force k x + c ẋ vanishes, i.e. ẍ = 0, where it leaves with ẋ = −e v₀ (x > 0 still). For
ζ < 1, with ω_d = ω₀√(1−ζ²), x = (v₀/ω_d) e^{−ζω₀t} sin ω_d t, ẍ = 0 at
ω_d t_s = atan2(2ζ√(1−ζ²), 2ζ² − 1), and there ẋ = −v₀ e^{−ζω₀t_s}, so

    e(ζ) = exp(−ζ/√(1−ζ²) · atan2(2ζ√(1−ζ²), 2ζ² − 1))          (ζ < 1, e > e⁻² ≈ 0.135)

and for ζ > 1 (s₁,₂ = ω₀(−ζ ± √(ζ²−1))) t_s = 2 ln(s₂/s₁)/(s₁ − s₂), e = −(s₁e^{s₁t_s} −
s₂e^{s₂t_s})/(s₁ − s₂)/ω₀ … as computed by :func:`restitution_of_damping_ratio`; e(ζ) falls
monotonically from 1 (ζ = 0) to 0 (ζ → ∞) and is inverted by bracketing
(:func:`damping_ratio`). States: 0 open, 1 closed (force-carrying).
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from sarfe.hbm.laws.contract import ContactLaw, LawInputError, Linearization, NormalForce, Parameter
from sarfe.hbm.laws.rattle import NORMAL_STIFFNESS

PARAMETERS = (
    NORMAL_STIFFNESS,
    Parameter("contact_damping", "damping_N_s_m", "N s/m", "contact dashpot c (while closed)",
              minimum=0.0, default=0.0, split=True, scaled=True),
    Parameter("restitution", "restitution", "1",
              "coefficient of restitution e of one impact (instead of damping_N_s_m; 0: not given)",
              minimum=0.0, maximum=1.0, default=0.0),
    Parameter("effective_mass", "effective_mass_kg", "kg",
              "effective mass m of the pair for the restitution (default: 1/m = g M⁻¹ gᵀ)",
              minimum=0.0, split=True, from_model=True),
)


def restitution_of_damping_ratio(zeta: float) -> float:
    """e(ζ) of one impact on the damped stop with the no-pulling cut-off (module docstring)."""
    zeta = float(zeta)
    if zeta <= 0.0:
        return 1.0
    if abs(zeta - 1.0) < 1e-9:
        return math.exp(-2.0)
    if zeta < 1.0:
        root = math.sqrt(1.0 - zeta * zeta)
        return math.exp(-zeta / root * math.atan2(2.0 * zeta * root, 2.0 * zeta * zeta - 1.0))
    root = math.sqrt(zeta * zeta - 1.0)
    s1, s2 = -zeta + root, -zeta - root                 # ω₀ = 1
    t = 2.0 * math.log(s2 / s1) / (s1 - s2)
    return -(s1 * math.exp(s1 * t) - s2 * math.exp(s2 * t)) / (s1 - s2)


@lru_cache(maxsize=256)
def damping_ratio(restitution: float) -> float:
    """ζ with e(ζ) = ``restitution`` ∈ (0, 1]."""
    e = float(restitution)
    if e >= 1.0:
        return 0.0
    upper = 1.0
    while restitution_of_damping_ratio(upper) > e:
        upper *= 2.0
    from scipy.optimize import brentq   # scipy.optimize: 0.1 s of import, only for this law

    return brentq(lambda z: restitution_of_damping_ratio(z) - e, 0.0, upper, xtol=1e-14,
                  rtol=1e-14)


def dashpot(p):
    """c (n,) [N s/m]: ``contact_damping``, or 2 ζ(e) √(k m) where a restitution e > 0 is given."""
    e = np.asarray(p["restitution"], dtype=float)
    zeta = np.array([damping_ratio(x) if x > 0 else 0.0 for x in np.ravel(e)]).reshape(e.shape)
    from_e = 2.0 * zeta * np.sqrt(p["normal_stiffness"] * np.maximum(p["effective_mass"], 0.0))
    return np.where(e > 0, from_e, p["contact_damping"])


def normal(p, gap, w, wdot):
    k, c = p["normal_stiffness"], dashpot(p)
    penetration = np.asarray(w) - gap
    trial = k * penetration + (0.0 if wdot is None else c * wdot)
    closed = (penetration > 0.0) & (trial > 0.0)
    force = np.where(closed, trial, 0.0)
    return NormalForce(force, np.where(closed, k, 0.0) * np.ones_like(force),
                       np.where(closed, c, 0.0) * np.ones_like(force), closed)


def linearize(p, gap):
    k = np.asarray(p["normal_stiffness"], dtype=float)
    closed = np.asarray(gap) <= 0
    return Linearization(k, dashpot(p), np.where(closed, -k * gap, 0.0), closed)


def static_deflection(p, force):
    return force / p["normal_stiffness"]


def prepare(contact, resolve):
    """Case check: exactly one of damping_N_s_m and restitution, e in (0, 1]."""
    given = [key for key in ("damping_N_s_m", "restitution") if key in contact]
    if len(given) != 1:
        raise LawInputError("damping_N_s_m", "give exactly one of damping_N_s_m or restitution"
                            + (" (not both)" if given else ""))
    if "restitution" in contact and not 0.0 < contact["restitution"] <= 1.0:
        raise LawInputError("restitution", f"must be in (0, 1], got {contact['restitution']}")
    return {}


def check(p):
    if np.any((p["restitution"] > 0) & ~(p["effective_mass"] > 0)):
        raise ValueError("effective_mass of a damped_impact contact with a restitution must be > 0")


LAW = ContactLaw(
    name="damped_impact",
    summary="penalty spring + dashpot while closed, no pulling: λ_n = max(0, k_n (w − g) + c ẇ)",
    parameters=PARAMETERS, normal=normal, linearize=linearize,
    static_deflection=static_deflection, velocity_dependent=True, prepare=prepare, check=check,
)
