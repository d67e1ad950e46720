r"""Squeak: Jenkins element — tangential spring k_t in series with a Coulomb slider (limit μ λ_n).

Slider position w (in the tangent plane, 1 or 2 directions), tangential relative displacement q:

    λ_t = k_t (q − w),     |λ_t| ≤ μ λ_n.

One time step (the return map) projects the previous slider position onto the disk of radius
ρ = μ λ_n / k_t around q:

    w_j = q_j + Proj_{|x| ≤ ρ_j}(w_{j−1} − q_j)

states: separation (λ_n = 0: ρ = 0, the slider follows, λ_t = 0), stick (w_j = w_{j−1}),
slip (the projection is active, |λ_t| = μ λ_n). In one tangential direction the projection is a
clamp, w_j = clip(w_{j−1}, q_j − ρ_j, q_j + ρ_j).
"""
from __future__ import annotations

import numpy as np

SEPARATED, STICK, SLIP = 0, 1, 2


def slider_update(slider_previous, tangential_displacement, slip_radius):
    """Return map of one step, broadcasting over leading axes; last axis = tangent directions.

    slider_previous, tangential_displacement: (..., n_t) [m]; slip_radius ρ = μ λ_n / k_t: (...) [m].
    Returns (slider (..., n_t) [m], state (...) int8 in {SEPARATED, STICK, SLIP}).
    """
    w_prev = np.asarray(slider_previous, dtype=float)
    q = np.asarray(tangential_displacement, dtype=float)
    rho = np.maximum(np.asarray(slip_radius, dtype=float), 0.0)
    trial = w_prev - q
    norm = np.sqrt(np.sum(trial * trial, axis=-1))
    slipping = norm > rho
    scale = np.where(slipping, rho / np.where(slipping, norm, 1.0), 1.0)
    slider = q + trial * scale[..., None]
    state = np.where(rho <= 0.0, SEPARATED, np.where(slipping, SLIP, STICK)).astype(np.int8)
    return slider, state
