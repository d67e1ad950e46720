r"""Hill stability of a periodic solution (Floquet exponents from the harmonic-balance Jacobian).

A perturbation y = e^{st} p(θ) of the periodic solution obeys the linearized periodic system; with
p in the same truncated Fourier basis (all kept DOFs), this is the quadratic eigenproblem

    ( s² M̃ + s D̃ + ∂R/∂ũ ) p̃ = 0,     M̃ = I⊗M,   D̃ = I⊗D + 2ω ∇⊗M + (I⊗G)ᵀ E diag(∂λ/∂ṙ) Φ (I⊗G),
    ∂R/∂ũ = S(ω) + (I⊗G)ᵀ ∂λ̃/∂r̃ (I⊗G)   (the Newton Jacobian on all DOFs),

the last term of D̃ (``contact_damping``) being the velocity terms of rate-dependent contact laws
(δṙ = s δr + ω ∂δr/∂θ; the ω∂/∂θ part is already in ∂λ̃/∂r̃),

solved in first-order form [[0, I], [−∂R/∂ũ, −D̃]] z = s [[I, 0], [0, M̃]] z: densely when
2(2H+1)n ≤ ``dense_limit``, else by sparse shift-invert (ARPACK, σ = 0) for the eigenvalues nearest
the origin. The (2H+1)·2n eigenvalues are the 2n Floquet exponents repeated with shifts i k ω plus
truncation artefacts; following Krack & Gross (2019, §3.6) we keep the 2n with the smallest |Im s|
(the ones whose eigenvectors are dominated by the low harmonics), plus any further eigenvalue in
the strip |Im s| ≤ 1.01 ω/2 (at a period-doubling the two exponents of a real multiplier pair and
their conjugates all sit near Im s = ±ω/2, ~0.2 % off with truncation, and compete for two places;
without this the unstable one was dropped on NLvib example 03). The solution is stable when the
largest real part of the kept exponents ≤ tolerance · ω. 
Nonsmooth contacts (:mod:`sarfe.hbm.stability.contact_terms`): the Newton Jacobian is not Hill's
operator for them. A Jenkins element remembers the perturbation of its last slip sample, which
grows or decays with e^{st} meanwhile, so its term is 𝒥(s), and the eigenproblem is nonlinear in s:

    T(s) p̃ = ( s² M̃ + s D̃ + S(ω) + (I⊗G)ᵀ 𝒥(s) (I⊗G) ) p̃ = 0;

the normal laws keep their N-sampled Jacobian. The exponents of the frozen problem
(𝒥(0), the harmonic-map Jacobian) are the starting points; the leading ones are refined by
secant updates on the fixed point of successive linear problems (:func:`refine_exponent`) until
the largest real part belongs to a refined exponent. The verdict is ``None`` with a note when it
cannot be trusted: the refinement did not converge, or the leading exponent lies within the band
|Re s| ≤ ``uncertain_band`` · ω of 0 (a fold or bifurcation within the truncation error).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from sarfe.hbm.dynamic_stiffness import hill_matrices


@dataclass(frozen=True)
class StabilityResult:
    """stable (True | False | None: uncertain), leading max Re s [1/s] (nan if not computed),
    note (why the verdict is None, or '' ), exponents: the kept exponents (complex, 1/s)."""

    stable: object
    leading: float
    note: str
    exponents: np.ndarray


def floquet_exponents(model, omega, harmonics, jacobian, dense_limit=3000, max_exponents=120,
                      contact_damping=None):
    """Kept Floquet exponents s [1/s] (≥ 2n) of the frozen problem, given ∂R/∂ũ (sparse or dense).

    On the sparse path at most ``max_exponents`` exponents nearest the origin are computed (all 2n
    representatives lie in the strip |Im s| ≤ ω/2, hence near 0; for 2n > max_exponents only the
    ones of the lowest modes are checked). contact_damping: (I⊗G)ᵀ E diag(∂λ/∂ṙ) Φ (I⊗G) or None.
    """
    n = model.dof_count
    Mt, Dt = _hill(model, omega, harmonics, contact_damping)
    size = Mt.shape[0]
    keep = 2 * n
    dense = 2 * size <= dense_limit
    if dense:
        values = np.linalg.eigvals(_first_order(Mt, Dt, jacobian, dense)[0])
    else:
        keep = min(keep, max_exponents)
        count = min(2 * size - 2, keep + max(20, keep // 2))
        OPinv = _shift_invert(Mt, Dt, jacobian, 0.0)
        values = spla.eigs(_pencil_operator(Mt, Dt, jacobian, OPinv.dtype), k=count,
                           M=sp.block_diag([sp.identity(size), Mt], format="csr"), sigma=0.0,
                           which="LM", return_eigenvectors=False, OPinv=OPinv,
                           v0=start_vector(2 * size, OPinv.dtype))
    return _select(values, omega, keep)


def start_vector(size, dtype=float):
    """A fixed ARPACK start vector (seeded, not ARPACK's random one): the same exponents to the
    last bit in every run and every worker process."""
    vector = np.random.default_rng(0).standard_normal(size)
    return vector.astype(dtype)


def _hill(model, omega, harmonics, contact_damping):
    Mt, Dt = hill_matrices(model, omega, harmonics)
    if contact_damping is not None:
        Dt = (Dt + sp.csr_matrix(contact_damping)).tocsr()
    return Mt, Dt


def _first_order(Mt, Dt, jacobian, dense):
    """(A, B) of the first-order Hill pencil A z = s B z (dense: B⁻¹A as A, B None)."""
    size = Mt.shape[0]
    if dense:
        Minv = np.linalg.inv(_dense(Mt))
        A = np.block([[np.zeros((size, size)), np.eye(size)],
                      [-Minv @ _dense(jacobian), -Minv @ _dense(Dt)]])
        return A, None
    A = sp.bmat([[None, sp.identity(size)], [-sp.csr_matrix(jacobian), -Dt]], format="csc")
    B = sp.block_diag([sp.identity(size), Mt], format="csc")
    return A, B


DENSE_FILL = 0.1     # Q(σ) with more non-zeros than this fraction of its entries: dense LU


def _shift_invert(Mt, Dt, jacobian, sigma):
    r"""(A − σB)⁻¹ of the first-order pencil (:func:`_first_order`) as a LinearOperator, through
    the quadratic Q(σ) = σ² M̃ + σ D̃ + ∂R/∂ũ of half its order: (A − σB)(x, y) = (b₁, b₂) gives

        x = −Q(σ)⁻¹ (b₂ + (D̃ + σ M̃) b₁),     y = b₁ + σ x,

    one factorization of Q(σ): dense LU where ∂R/∂ũ fills more than ``DENSE_FILL`` of it (the
    contact rows of a Ritz-basis problem couple all harmonics: a sparse LU of the first-order
    pencil took 0.9 s there, a dense one of Q 0.1-0.5 s), else SuperLU. Real for real σ and real
    matrices, else complex."""
    size = Mt.shape[0]
    dtype = np.result_type(jacobian.dtype, Dt.dtype, Mt.dtype,
                           complex if np.iscomplexobj(sigma) else float)
    coupling = (sp.csr_matrix(Dt) + sigma * sp.csr_matrix(Mt)).astype(dtype).tocsr()
    if _filled(jacobian):
        Q = _dense(jacobian).astype(dtype)
        Q += sigma * Dt.toarray() if sp.issparse(Dt) else sigma * np.asarray(Dt)
        Q += sigma * sigma * (Mt.toarray() if sp.issparse(Mt) else np.asarray(Mt))
        factor = sla.lu_factor(Q, overwrite_a=True, check_finite=False)
        solve = lambda b: sla.lu_solve(factor, b, check_finite=False)  # noqa: E731
    else:
        Q = sp.csc_matrix(jacobian) + sigma * sp.csc_matrix(Dt) + sigma * sigma * sp.csc_matrix(Mt)
        solve = spla.splu(Q.astype(dtype).tocsc()).solve

    def apply(z):
        z = np.asarray(z).reshape(-1)
        if np.iscomplexobj(z) and not np.iscomplexobj(np.empty(0, dtype)):
            return apply(z.real) + 1j * apply(z.imag)
        b1, b2 = z[:size], z[size:]
        x = -solve((b2 + coupling @ b1).astype(dtype))
        return np.concatenate([x, b1 + sigma * x])

    return spla.LinearOperator((2 * size, 2 * size), matvec=apply, dtype=dtype)


def _pencil_operator(Mt, Dt, jacobian, dtype):
    """A of the first-order pencil as a LinearOperator z = (x, y) ↦ (y, −∂R/∂ũ x − D̃ y) (ARPACK's
    shift-invert mode reads only its shape and type: no block matrix is assembled)."""
    size = Mt.shape[0]
    J = jacobian if isinstance(jacobian, np.ndarray) else sp.csr_matrix(jacobian)
    D = sp.csr_matrix(Dt)

    def apply(z):
        z = np.asarray(z).reshape(-1)
        return np.concatenate([z[size:], -(J @ z[:size]) - D @ z[size:]])

    return spla.LinearOperator((2 * size, 2 * size), matvec=apply, dtype=dtype)


def _select(values, omega, keep):
    """The ``keep`` values with the smallest |Im s| and every other one in |Im s| ≤ 1.01 ω/2."""
    values = values[np.isfinite(values)]
    order = np.argsort(np.abs(values.imag), kind="stable")
    in_strip = np.abs(values.imag[order]) <= 0.5 * abs(omega) * (1 + 1e-2)
    in_strip[:keep] = True
    return values[order[in_strip]]


def _nearest(Mt, Dt, jacobian, target, dense, count=3):
    """Eigenvalues of the frozen pencil nearest ``target`` (complex allowed)."""
    if dense:
        A, _ = _first_order(Mt, Dt, jacobian, dense)
        if A.shape[0] <= 64:
            values = np.linalg.eigvals(A)
            return values[np.argsort(np.abs(values - target))[:count]]
        # shift-invert on a dense LU: the few values near the target, not all of them
        return spla.eigs(A.astype(complex), k=count, sigma=target, which="LM",
                         return_eigenvectors=False, v0=start_vector(A.shape[0], complex))
    size = Mt.shape[0]
    return spla.eigs(_pencil_operator(Mt, Dt, jacobian, complex), k=count,
                     M=sp.block_diag([sp.identity(size), Mt], format="csr").astype(complex),
                     sigma=target, which="LM", return_eigenvectors=False,
                     OPinv=_shift_invert(Mt, Dt, jacobian, complex(target)),
                     v0=start_vector(2 * size, complex))


def refine_exponent(Mt, Dt, jacobian, operator, s0, dense, iterations=30, tolerance=1e-9):
    r"""Solve the nonlinear Hill problem T(s) p = 0, T(s) = s²M̃ + sD̃ + ∂R/∂ũ + C(s), from s0.

    μ(s): the eigenvalue of the pencil frozen at C(s) nearest s; the exponent is the fixed point
    s = μ(s) (the root of f(s) = μ(s) − s, analytic in s [1/s]). Secant updates in s,

        s_{k+1} = s_k − f(s_k) (s_k − s_{k−1}) / (f(s_k) − f(s_{k−1})),

    start from s_1 = μ(s0) (one successive-linear step, the fallback also where the secant's
    denominator vanishes): superlinear where the plain iteration s_{k+1} = μ(s_k) converges
    linearly at rate |μ'(s)| (Jenkins 1-DOF near the peak: ≈ 15 eigen-solves → ≈ 5). Converged when
    |μ(s_k) − s_k| ≤ tolerance · max(|μ(s_k)|, 1). Small (dense) problems build C(s) dense
    (``operator.dense_correction``) and keep ∂R/∂ũ dense once. Returns (s, converged)."""
    s = complex(s0)
    as_array = dense or _filled(jacobian)        # (a Ritz-basis problem: all harmonics coupled)
    dense_correction = getattr(operator, "dense_correction", None) if as_array else None
    base = _dense(jacobian) if as_array else sp.csr_matrix(jacobian)
    previous = None                                       # (s_{k−1}, f(s_{k−1}))
    for _ in range(iterations):
        if dense_correction is not None:
            J = base + dense_correction(s)
        else:
            J = base + (operator.correction(s).toarray() if as_array else operator.correction(s))
        new = _nearest(Mt, Dt, J, s, dense, count=1)[0]
        residual = new - s
        if abs(residual) <= tolerance * max(abs(new), 1.0):
            return new, True
        step = new                                        # successive linear problems
        if previous is not None:
            slope = residual - previous[1]
            if abs(slope) > 1e-300:
                step = s - residual * (s - previous[0]) / slope
        previous = (s, residual)
        s = step
    return s, False


def hill_stability(model, omega, harmonics, jacobian, tolerance=1e-6, dense_limit=3000,
                   contact_damping=None, operator=None, uncertain_band=1e-4, max_refined=12):
    """Hill stability of a periodic solution (module docstring) → :class:`StabilityResult`.

    operator: a :class:`sarfe.hbm.stability.contact_terms.ContactOperator` (the contact term at s), or
    None (the frozen problem on ``jacobian`` alone, smooth laws)."""
    try:
        if operator is not None:
            if _filled(jacobian) and hasattr(operator, "dense_correction"):
                jacobian = _dense(jacobian) + operator.dense_correction(0.0).real
            else:
                jacobian = sp.csr_matrix(jacobian) + operator.correction(0.0).real
        values = floquet_exponents(model, omega, harmonics, jacobian, dense_limit,
                                   contact_damping=contact_damping)
        if values.size == 0:
            return StabilityResult(None, float("nan"), "no Floquet exponent found", values)
        note = ""
        if operator is not None and operator.has_memory:
            values, note = _refine_leading(model, omega, harmonics, jacobian, contact_damping,
                                           operator, values, dense_limit, max_refined)
    except (np.linalg.LinAlgError, RuntimeError, ValueError, spla.ArpackError) as error:
        return StabilityResult(None, float("nan"), f"eigen-solve failed: {error}", np.zeros(0))
    leading = float(values.real.max())
    if note:
        return StabilityResult(None, leading, note, values)
    return verdict(leading, values, omega, tolerance, uncertain_band)


def verdict(leading, exponents, omega, tolerance, uncertain_band):
    """The verdict on a located leading exponent [1/s]: uncertain (None, with a note) within
    ±``uncertain_band``·|ω| of 0, else stable iff leading ≤ ``tolerance``·|ω|."""
    if abs(leading) <= uncertain_band * abs(omega):
        return StabilityResult(None, leading, f"leading Floquet exponent {leading:.3g} 1/s within "
                               f"±{uncertain_band:g}·ω of 0 (near a fold or bifurcation)", exponents)
    return StabilityResult(bool(leading <= tolerance * abs(omega)), leading, "", exponents)


def _refine_leading(model, omega, harmonics, jacobian, contact_damping, operator, values,
                    dense_limit, max_refined):
    """Refine the frozen exponents on the nonlinear problem, largest real part first, until the
    largest real part is a refined one. Returns (values, note)."""
    Mt, Dt = _hill(model, omega, harmonics, contact_damping)
    dense = 2 * Mt.shape[0] <= dense_limit
    values = np.array(values, dtype=complex)
    refined = np.zeros(values.size, bool)
    for _ in range(max_refined):
        upper = np.flatnonzero(values.imag >= 0)
        open_ = upper[~refined[upper]]
        if open_.size == 0:
            break
        lead = upper[np.argmax(values.real[upper])]
        if refined[lead]:
            break
        i = open_[np.argmax(values.real[open_])]
        s, converged = refine_exponent(Mt, Dt, jacobian, operator, values[i], dense)
        if not converged:
            return values, (f"Hill exponent {values[i]:.4g} 1/s did not converge on the "
                            "nonlinear (friction memory) eigenproblem")
        mirror = np.flatnonzero(np.abs(values - np.conj(values[i])) <= 1e-12 * max(abs(values[i]), 1))
        radius = 2.0 * abs(values[i] - s)
        values[i] = s
        refined[i] = True
        for m in mirror:
            if m != i:
                values[m], refined[m] = np.conj(s), True
        for root in (s, np.conj(s)):
            _shifted_copies(values, refined, root, omega, harmonics, radius)
    else:
        return values, "Hill exponents: refinement budget exhausted before the leading one"
    return values, ""


def _shifted_copies(values, refined, s, omega, harmonics, radius):
    """Mark the frozen exponents that are shifted copies of the refined exponent s as refined,
    in place: Floquet exponents are defined modulo iω, so s + ikω (0 < |k| ≤ 2H: two copies in
    the 2H+1 harmonic rows differ by up to 2H) is an exponent too, and a not yet refined value within ``radius`` (twice the distance the refinement moved
    the frozen exponent of s) of it is that copy, given its value. Without this each of the up to
    2H copies of one exponent, their frozen real parts spread by the truncation (squeak rig, H = 5,
    50 Hz: −12.5 … −13.4 1/s, all refining to −13.45), was refined in turn and the budget ran out
    before the leading one."""
    k = np.round((values.imag - s.imag) / omega)
    shifted = s + 1j * k * omega
    copies = (~refined & (k != 0) & (np.abs(k) <= 2 * harmonics)
              & (np.abs(values - shifted) <= radius))
    values[copies] = shifted[copies]
    refined[copies] = True


def _filled(matrix):
    """An ndarray, or a sparse matrix with more than ``DENSE_FILL`` of its entries non-zero."""
    if not sp.issparse(matrix):
        return True
    return matrix.nnz > DENSE_FILL * matrix.shape[0] * matrix.shape[1]


def _dense(matrix):
    return matrix.toarray() if sp.issparse(matrix) else np.asarray(matrix)
