r"""The default (``'auto'``) stability verdict: the contact-row count at H, trusted only where the
count at a coarser contact coupling agrees.

Hill's truncation at H harmonics has two parts. The linear structure is truncated on the full
Hill matrix (:mod:`sarfe.hbm.stability.hill`): its modes above ~Hω cannot be folded into the strip
|Im s| ≤ ω/2 and come back as edge eigenvalues at Im s ≈ 2…5ω, whose real parts are artefacts
(on the shipped rattle rig at H = 10 the full method called 307 of 363 points unstable and
contradicted time integration at 24 of the 34 points where the integrator's verdict converged,
benchmarks/results/stability.md). On the contact rows
(:mod:`sarfe.hbm.stability.rows`) the structure is exact, C(s) from the modal compliance at every
shifted exponent s ± ikω, and only the contact coupling 𝒥(s) is truncated at H: this is the
verdict used. What remains is the contact truncation itself: an impact's Jacobian is a train of
steps in time, whose Fourier series converges slowly, and near a fold or a grazing the exponents
nearest the axis move by more than their distance from it when H changes. So the count is
repeated with the contact coupling cut to H' = ⌊3H/4⌋ harmonics (the same orbit, the same AFT
Jacobian, its (2H'+1)-row Galerkin block — no re-solve; the leading (cos, sin) rows of each block
in the harmonic-major order, and the friction memory at H', the leading block of that at H),
on the contour of the count at H and from the same LU
(:func:`sarfe.hbm.stability.rows.contact_row_counts`), and

    unstable at H (an exponent right of −ε located or counted) and no zero right of −ε at H',
    or stable at H (no zero right of −ε) and zeros right of −ε at H'

is reported as not resolved: ``stable`` None with a note naming both counts. A single real zero
right of the band at H is not checked: it is the exponent of a fold's middle branch (one real
exponent crosses 0 where ω turns on the branch, with the sign of det F(0), i.e. of the Newton
Jacobian's determinant), which the truncated coupling moves along the real axis, not off it (the
lumped damped-impact chain's middle branch kept 'unstable', NLvib 03's too). Measured against the
time integrator's monodromy (:func:`sarfe.hbm.stability.perturbation.perturbation_check`) in
benchmarks/bench_stability.py (``--truth``) and tests/hbm/stability/test_stability_trust.py.

Where the count at H finds two or more exponents right of −ε they are located from its samples
(:mod:`sarfe.hbm.stability.zeros`) and checked the same way; the Ritz method
(:mod:`sarfe.hbm.stability.condensed`) is left for the points where they are not all located; a
model without a modal basis (sparse lumped models, damping not diagonal in the modes) keeps the
full Hill method up to ``FULL_UP_TO`` Hill rows.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from sarfe.hbm.residual import Problem
from sarfe.hbm.stability.contact_terms import ContactOperator
from sarfe.hbm.stability.rows import contact_row_count, stability_basis

FULL_UP_TO = 3000     # Hill rows 2(2H+1)n up to which a model without a modal basis uses 'full'


def check_harmonics(harmonics: int) -> int:
    """H' = ⌊3H/4⌋, the contact coupling of the check (0 for H ≤ 1: no check)."""
    return (3 * int(harmonics)) // 4


def auto_method(problem) -> str:
    """'contact_rows' for a model with contacts and a modal basis (any size), else 'full' up to
    ``FULL_UP_TO`` Hill rows, else 'contact_rows' (the Ritz method then decides)."""
    if not problem.contacts.count:
        return "full"
    if stability_basis(problem.model) is not None:
        return "contact_rows"
    size = 2 * (2 * problem.harmonics + 1) * problem.model.dof_count
    return "full" if size <= FULL_UP_TO else "contact_rows"


def truncated_forces(forces, harmonics: int):
    """The AFT result with its Jacobian blocks cut to the first 2H'+1 harmonic rows: the Galerkin
    block of the same linearization (local order h·m + l, so the leading (2H'+1)m entries)."""
    def cut(blocks):
        P = 2 * harmonics + 1
        return [(rows, block[:, :P * rows.shape[1], :P * rows.shape[1]]) for rows, block in blocks]
    return replace(forces, blocks=cut(forces.blocks), damping_blocks=cut(
        forces.damping_blocks) if forces.damping_blocks else forces.damping_blocks)


def count_at(problem, omega, U, forces, harmonics, tolerance):
    """(StabilityResult or None, zeros) of the contact-row count of the same orbit with the
    contact coupling cut to ``harmonics`` < H (:func:`truncated_forces`; the friction memory
    rebuilt at that order), on its own contour: the check the default computed before it shared
    the count's contour (:func:`checked`), kept as the reference of that shared count (tests)."""
    forces = truncated_forces(forces, harmonics)
    coarse = Problem(problem.model, problem.contacts, problem.excitation[:2 * harmonics + 1],
                     harmonics, problem.samples_per_period, problem.friction_tolerance,
                     problem.friction_pass_cap)
    operator = ContactOperator(coarse, U, omega, forces)
    return contact_row_count(problem.model, problem.contacts, omega, harmonics, forces, operator,
                             tolerance=tolerance)


def checked(result, zeros, coarse, problem):
    """``result`` (the verdict at H; ``zeros``: exponents counted right of −ε, or None) unless the
    count at H' = :func:`check_harmonics` (``coarse``, from the same contour:
    :func:`sarfe.hbm.stability.rows.contact_row_counts`; None where it did not close) contradicts
    it (module docstring): then None with a note. A single real exponent right of the band (a
    fold's middle branch) is not checked."""
    H_coarse = check_harmonics(problem.harmonics)
    if result.stable is None or zeros is None or zeros == 1 or H_coarse < 1 or coarse is None:
        return result
    if (result.stable is True and coarse > 0) or (result.stable is False and coarse == 0):
        return replace(result, stable=None, note=(
            f"not resolved in H: {zeros} Floquet exponent(s) right of −1e-4·ω with the contact "
            f"coupling at H = {problem.harmonics}, {coarse} at H = {H_coarse}" + (
                f" (leading {result.leading:.3g} 1/s)" if np.isfinite(result.leading) else "")))
    return result
