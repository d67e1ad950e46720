r"""Rattle: unilateral penalty contact in the normal direction (node to node, or against ground).

    λ_n(w) = k_n · max(0, w − g)

w: relative normal displacement, positive closing the gap [m]; g: initial gap [m] (g > 0 open,
g = 0 touching, g < 0 overclosure = preload k_n·|g|); k_n: normal penalty stiffness [N/m].
Rate independent; exactly linear while closed (the pruning screen may turn a never-opening pair
into a spring k_n).
"""
from __future__ import annotations

import numpy as np

from sarfe.hbm.laws.contract import ContactLaw, Linearization, NormalForce, Parameter

NORMAL_STIFFNESS = Parameter("normal_stiffness", "normal_stiffness_N_m", "N/m",
                             "normal penalty stiffness k_n", minimum=0.0, exclusive=True,
                             required=True, split=True, scaled=True, normal_part=True)


def penalty_force(closing_displacement, gap, normal_stiffness):
    """λ_n = k_n max(0, w − g) and ∂λ_n/∂w = k_n where closed (w > g), broadcasting over
    (samples × contacts). Returns (λ_n [N], ∂λ_n/∂w [N/m], closed bool)."""
    penetration = np.asarray(closing_displacement) - gap
    closed = penetration > 0.0
    force = np.where(closed, normal_stiffness * penetration, 0.0)
    stiffness = np.where(closed, normal_stiffness, 0.0) * np.ones_like(force)
    return force, stiffness, closed


def normal(p, gap, w, wdot):
    force, stiffness, closed = penalty_force(w, gap, p["normal_stiffness"])
    return NormalForce(force, stiffness, None, closed)


def penalty_linearization(p, gap, normal_load=0.0):
    """k_n, preload −k_n g (+ N0) where g ≤ 0 (closed at u = 0)."""
    k = np.asarray(p["normal_stiffness"], dtype=float)
    closed = np.asarray(gap) <= 0
    preload = np.where(closed, -k * gap, 0.0) + normal_load
    return Linearization(k, np.zeros_like(k), preload, closed)


def linearize(p, gap):
    return penalty_linearization(p, gap)


def static_deflection(p, force):
    return force / p["normal_stiffness"]


LAW = ContactLaw(
    name="rattle",
    summary="unilateral penalty contact: λ_n = k_n max(0, w − g)",
    parameters=(NORMAL_STIFFNESS,),
    normal=normal, linearize=linearize, static_deflection=static_deflection,
    linear_when_closed=True,
)
