r"""Rattle: unilateral penalty contact in the normal direction (node to node, or against ground).

    λ_n(w) = k_n · max(0, w − g)

w: relative normal displacement, positive closing the gap [m]; g: initial gap [m] (g > 0 open,
g = 0 touching, g < 0 overclosure = preload k_n·|g|); k_n: normal penalty stiffness [N/m].
"""
from __future__ import annotations

import numpy as np


def normal_force(closing_displacement, gap, normal_stiffness):
    """Pointwise penalty law, broadcasting over contacts × time samples.

    Returns (λ_n [N], ∂λ_n/∂w [N/m]) with ∂λ_n/∂w = k_n where closed (w > g), else 0.
    """
    penetration = np.asarray(closing_displacement) - gap
    closed = penetration > 0.0
    force = np.where(closed, normal_stiffness * penetration, 0.0)
    stiffness = np.where(closed, normal_stiffness, 0.0) * np.ones_like(force)
    return force, stiffness
