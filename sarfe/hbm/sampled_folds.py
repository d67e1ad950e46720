r"""Turns of ω that the AFT sampling makes: a fold of the N-sample branch with the branch going on
just past it (:mod:`sarfe.hbm.continuation`).

With N samples a penalty force is piecewise linear in ũ (a sample enters or leaves contact at each
kink). On a lightly damped resonance, where the branch's slope dω/d‖ũ‖ is small, a kink can turn
the slope's sign: the N-sample branch zig-zags (fold, a piece back, fold, on) across a width that
shrinks with N, and a continuation that follows the first fold runs back along a ghost piece next
to its own branch. Measured on cases/lumped_rattle.yaml with modal ζ = 10⁻⁴ at the bracket's 2ω
resonance (55.22 Hz, N = 2048): the piece back is a second solution 2.5 % off the branch in the
panel's sin ω t coefficient, 0.013 Hz wide; with N = 8192 and 32768 Newton from either lands on one
solution (agreeing to 6·10⁻⁴ in that coefficient): the fold is the sampling's, not the model's. At
N = 256 such a piece back was 0.28 Hz wide (56.77 → 56.50 Hz).

A genuine fold has no solution just past it on the branch's side; a sampled one has the branch
going on there. :func:`step_over` solves at fixed ω a little past the turn (shares ``STEP_OVER`` of
the band, smallest first) from the last point and accepts the first converged point that lies
ahead along the direction of travel (cosine with the last secant > ``COS_ONWARD``, in scaled
unknowns z = (x / x_s, ω / ω_s)). What it steps over (the zig-zag, narrower than that share) is not
reported; the point's ``reason`` says so (``STEPPED_FOLD``).
"""
from __future__ import annotations

import numpy as np

STEP_OVER = (1e-4, 4e-4, 1.6e-3, 6.4e-3)   # shares of the band past a turn of ω tried
COS_ONWARD = 0.8         # the point past the turn: within ~37° of the direction of travel
TRAVEL_BASE = 1e-2       # the direction of travel: secant over at least this scaled length …
TRAVEL_POINTS = 20       # … or over the last this many points
STEPPED_FOLD = "stepped over a fold of the sampled branch"   # in the reason of the point past it


def step_over(solve_at, z, travel, span, direction, farthest=None):
    """A point of the branch just past a turn of ω at z, or None (a genuine fold).

    solve_at(ω [rad/s]) → (HarmonicSolution solved at fixed ω from the last point, its z);
    z: the last point (before the turn) in scaled unknowns; travel: the secant that led to it
    (z_i − z_{i−1}); span ω_s [rad/s]; direction ±1 of the sweep; farthest: the farthest scaled
    ω of the recent points (a zig-zag's points ahead of z; default z's). The shares are taken
    past it. Returns (point, z, share)."""
    norm = np.linalg.norm(travel)
    if norm == 0 or direction * travel[-1] <= 0:
        return None
    travel = travel / norm
    far = z[-1] if farthest is None else farthest
    for share in STEP_OVER:
        omega = (far + direction * share) * span
        point, z_new = solve_at(omega)
        if not point.converged:
            continue
        d = z_new - z
        if d @ travel > COS_ONWARD * np.linalg.norm(d):
            return point, z_new, share
    return None


def stepped_note(omega_turn, omega_new, share, span, samples):
    """The reason's addition for a point solved past a sampled fold (``STEPPED_FOLD``)."""
    return (f" ({STEPPED_FOLD} at {omega_turn / (2 * np.pi):.5g} Hz, N = {samples}: the branch "
            f"goes on at {omega_new / (2 * np.pi):.5g} Hz, solved at fixed ω; the zig-zag of the "
            f"N-sample branch there, narrower than {share * span / (2 * np.pi):.2g} Hz, is not "
            "reported)")
