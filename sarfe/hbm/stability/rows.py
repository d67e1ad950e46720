r"""Hill stability on the contact rows: count the Floquet exponents right of the imaginary axis
with the argument principle on det(I + C(s) 𝒥(s)), no eigen-solve of a Hill matrix.

Every exponent of Hill's operator T(s) that is not a (damped) exponent of the linear structure is a
zero of det F(s), F(s) = I + C(s) 𝒥(s) on the loaded contact rows, C(s) the structure's compliance
from its modal basis (:mod:`sarfe.hbm.stability.determinant`). The zeros in the half-strip
Ω = {−ε < Re s < X, |Im s| < 1.01 ω/2}, ε = uncertain_band·ω, are counted by the change of
arg det F along its boundary (:mod:`sarfe.hbm.stability.contour`).

No zero in Ω: stable, and every exponent has Re s < −ε. The count locates none of them: the
leading exponent is reported as not located (NaN) with a note stating the bound Re s < −ε
(:func:`not_located`). (It used to report the least damped exponent of the structure, max Re of
μ s² + δ s + 1 = 0, which is not the orbit's where a contact row is loaded: on the squeak rig at
50 / 100 / 150 Hz, H = 5, it said −3.95 1/s where the full Hill method's leading exponent is
−25.8 / −13.8 / −14.2 1/s; the contacts damp and stiffen the coupled modes, so the orbit's leading
exponent lay left of the structure's at every measured point (lumped_rattle at 45 Hz: −9.49
against −15.85 1/s; door trim at 40 / 52 Hz: −6.25 against −6.65 / −6.43 1/s);
tests/hbm/stability/test_stability_rows.py checks the bound against the full method.) Where no
contact row is loaded (every contact open all period) F = I, Hill's operator is the structure's
and its least damped exponent is the orbit's, reported as such. One zero in Ω: it is real (a
fold's exponent), located on the real axis by the sign of det F (:func:`sarfe.hbm.stability.zeros.real_zero`), and decides the
verdict (:func:`contact_row_stability`). Two or more: all of them are located from the count's
samples (:func:`sarfe.hbm.stability.zeros.located_zeros`) and the leading one decides. A pole near
the contour, a model without a modal basis, a contour that does not close on a multiple of π, or
zeros that are not all located: ``None`` — the caller then locates the exponents by the
Ritz-basis Hill method (:mod:`sarfe.hbm.stability.condensed`). The check of
:mod:`sarfe.hbm.stability.trust` (the contact coupling cut to H' < H) is counted along the same
contour from the same LU (:func:`contact_row_counts`,
:meth:`~sarfe.hbm.stability.determinant.ContactRowDeterminant.log_determinants`).
Measured against the full Hill method in tests/hbm/stability/test_stability_rows.py and
benchmarks/bench_stability.py.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

from sarfe.hbm.aft import jacobian_matrix
from sarfe.hbm.stability.contour import (exponent_bound, shifted_exponents, upper_contour,
                                         winding_counts)
from sarfe.hbm.stability.determinant import (ContactRowDeterminant, stability_basis,
                                             structural_exponents)
from sarfe.hbm.stability.hill import StabilityResult, verdict
from sarfe.hbm.stability.zeros import located_zeros, real_zero


def contact_row_stability(model, contacts, omega, harmonics, forces, operator=None,
                          uncertain_band=1e-4, tolerance=1e-6):
    """StabilityResult when the contact-row count decides it, else None (see
    :func:`contact_row_count`, which also returns the count)."""
    return contact_row_count(model, contacts, omega, harmonics, forces, operator, uncertain_band,
                             tolerance)[0]


def contact_row_count(model, contacts, omega, harmonics, forces, operator=None,
                      uncertain_band=1e-4, tolerance=1e-6):
    """(StabilityResult or None, zeros) of :func:`contact_row_counts` without the coarse count."""
    return contact_row_counts(model, contacts, omega, harmonics, forces, operator, uncertain_band,
                              tolerance)[:2]


def contact_row_counts(model, contacts, omega, harmonics, forces, operator=None,
                       uncertain_band=1e-4, tolerance=1e-6, check_harmonics=0):
    """(StabilityResult or None, zeros, coarse): zeros = the number of Floquet exponents right of
    −ε (None where the count did not close); coarse = the same count with the contact coupling
    cut to ``check_harmonics`` = H' (1 ≤ H' < H; else None), on the same contour and nodes
    (:meth:`ContactRowDeterminant.log_determinants`, :func:`winding_counts`: X of the coupling at
    H bounds every exponent at H' too, ‖𝒥'‖ ≤ ‖𝒥‖ being a leading block). The result when the
    count decides it, else None.

    No zero of det F right of −ε: stable (for every stability tolerance ≥ 0 of the full method),
    the leading exponent not located (NaN, :func:`not_located`) where a contact row is loaded.
    Exactly one: it is real (zeros off the real axis come in conjugate pairs) and it is the leading
    exponent s*; :func:`real_zero` locates it and the verdict is the full method's rule: uncertain
    (None, with a note) when |s*| ≤ ``uncertain_band``·ω, else stable iff s* ≤ ``tolerance``·ω —
    the middle branch of a fold is unstable here without an eigen-solve. (The Ritz basis of
    :mod:`sarfe.hbm.stability.condensed`, which these points went to before, reported 'stable'
    with a leading exponent near −7 1/s at three points of such a branch of the 12-pair door trim
    at 46.2 Hz, where det F changes sign at s* ≈ 1.2–3.5 1/s.) Two or more: every zero in the
    half-strip is located from the count's samples (:func:`leading_zeros`: Delves–Lyness power
    sums on a box, Muller's method, deflation) and the leading one decides by the same rule; None
    (the caller's Ritz method) only where fewer than the counted number are located.

    forces: the AFT :class:`ContactForces` of the orbit (all harmonic rows, blocks computed);
    operator: the :class:`ContactOperator` (friction memory) or None. See the module docstring.
    """
    basis = stability_basis(model)
    if basis is None or model.dof_count == 0:
        return None, None, None
    omega, H = abs(float(omega)), int(harmonics)
    coarse = int(check_harmonics) if 1 <= int(check_harmonics) < H else None
    epsilon = uncertain_band * omega
    structure = structural_exponents(basis.flexibility, basis.damping)
    least_damped = float(structure.real.max())
    if not least_damped < -2.0 * epsilon:       # a pole on or right of the contour
        return None, None, None
    n_rows = contacts.row_count
    J = jacobian_matrix(forces.blocks, n_rows, H)
    Jd = jacobian_matrix(forces.damping_blocks, n_rows, H) if forces.damping_blocks else None
    det = ContactRowDeterminant(basis, contacts.gap_map, omega, H, J, Jd, operator)
    if det.loaded.size == 0:                    # F = I: the orbit's exponents are the structure's
        return (StabilityResult(True, least_damped, "", structure), 0,
                None if coarse is None else 0)
    stable = not_located(epsilon)
    # ‖𝒥(s)‖₂ for Re s ≥ 0: twice its largest value at s = 0, ω, 10ω (the memory factors e^{−shd}
    # have modulus ≤ 1 there; the pointwise part does not depend on s), each bounded above by the
    # Frobenius norm (‖·‖₂ ≤ ‖·‖_F: X only grows, the contour still encloses every exponent)
    jacobian_norm = 2.0 * float(np.linalg.norm(det.probe_terms, axis=(1, 2)).max())
    damping_norm = 0.0 if Jd is None else float(spla.norm(Jd))
    X = exponent_bound(basis, det.gap_modes, omega, H, jacobian_norm, damping_norm)
    top = 0.505 * omega                                   # the strip |Im s| ≤ 1.01 ω/2
    poles = shifted_exponents(structure, omega, H)
    contour = upper_contour(epsilon, X, top, poles)
    samples = {}                # log det F at the contour's nodes, for locating ≥ 2 zeros

    def sampled(s):
        values = det.log_determinants(s, coarse=coarse)
        samples.update(zip(np.asarray(s).tolist(),
                           (values if coarse is None else values[:, 0]).tolist()))
        return values

    counts, _ = winding_counts(sampled, contour)
    closed = [None if not np.isfinite(c) or abs(c - round(c)) > 0.1 else int(round(c))
              for c in counts]
    zeros, coarse_zeros = closed[0], (closed[1] if coarse is not None else None)
    if zeros is None:
        return None, None, coarse_zeros
    if zeros == 0:
        return stable, 0, coarse_zeros
    if zeros == 1:
        lead = real_zero(det.log_determinants, -epsilon, X)
        exponents = None if lead is None else np.array([lead])
    else:
        exponents = leading_zeros(det.log_determinants, samples, zeros, epsilon, top, X, poles)
    if exponents is None:
        return None, zeros, coarse_zeros
    lead = float(exponents.real.max())
    return verdict(lead, np.concatenate([exponents, structure]), omega, tolerance,
                   uncertain_band), zeros, coarse_zeros


def not_located(epsilon):
    """The StabilityResult of a count with no zero right of −ε (``epsilon`` [1/s]) and a loaded
    contact row: stable, leading exponent NaN (not located: the count bounds the exponents, it
    does not find them), exponents empty, and a note that states the bound Re s < −ε."""
    return StabilityResult(True, float("nan"), (
        f"leading Floquet exponent not located: the contact-row count finds none right of "
        f"−1e-4·ω, every exponent has Re s < {-epsilon:.3g} 1/s"), np.zeros(0, complex))


def leading_zeros(log_det, samples, zeros, epsilon, top, X, poles=()):
    """Every zero of det F in the half-strip Ω of the count (``zeros`` ≥ 2 of them), conjugates
    included ((zeros,) complex [1/s]), located from the count's ``samples`` (dict s ↦ log det F)
    by :func:`sarfe.hbm.stability.zeros.located_zeros` (``poles``: those of det F,
    :func:`shifted_exponents`); None when not all are located."""
    found = located_zeros(log_det, samples, zeros, epsilon, top, X, poles)
    if found is None:
        return None
    return np.concatenate([found, found[found.imag != 0].conj()])
