r"""The contact term of Hill's eigenproblem: the linearized periodic contact forces at exponent s.

A perturbation δr(t) = e^{st} p(θ) of the contact displacements (p periodic) changes the contact
forces by δλ(t) = e^{st} 𝒥(s) p. For a pointwise law 𝒥 is the AFT Jacobian E diag(∂λ/∂w) Φ,
independent of s. Two things make the harmonic-map Jacobian of the Newton solver the wrong operator
for stability:

1. **Memory (Jenkins tangent element).** The slider obeys ẇ = 0 in stick, so the linearized slider
   keeps the perturbation of the last slip sample j(i): δw_i = e^{−s(t_i − t_j)}·(…)_j. With the
   Floquet factor the linearized return map of one sample is

       ŵ_j = P_j (e^{−sh} ŵ_{j−1} − p̂_j) + p̂_j + n_j dρ_j,    δλ̂_t,j = k_t (p̂_j − ŵ_j),

   and periodicity ŵ_{−1} = ŵ_{N−1} gives ŵ_{−1} = (I − e^{−sT} A)⁻¹ B(s), A = Π P_j (P_j, n_j of
   :func:`sarfe.hbm.laws.jenkins.slider_update_derivatives`; h = T/N). The harmonic-map Jacobian is
   this at s = 0: it treats the memory as if the perturbation did not grow or decay, which on the
   squeak rig turned an orbit that time integration finds attracting into Re s ≈ +128…+180 1/s.
   𝒥(s) is complex for complex s and depends on s non-polynomially (a nonlinear eigenproblem).
2. **Kinks (unilateral springs, stick/slip normal forces).** The sampled ∂λ/∂w jumps at a contact
   crossing, quantized to one sample; near a fold det ∂R/∂ũ can change sign by this alone. The
   normal part can be re-evaluated on ``refine`` × N samples (default 1: off — on NLvib example
   03 the 8N Jacobian of the N-sampled orbit disagreed more often with time integration than the
   N-sampled one, the orbit and its Jacobian must come from the same discrete system).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from sarfe.hbm import harmonics as hm
from sarfe.hbm import laws
from sarfe.hbm.aft import curvature_blocks, jacobian_matrix, pointwise_jacobian, tangential_samples
from sarfe.hbm.laws import curvature
from sarfe.hbm.laws.jenkins import jenkins_periodic_1d, last_reset_index, slider_update_derivatives


def _normal_part(law, p, contacts, idx, R, omega, N):
    """λ_n (N, n_g), ∂λ_n/∂w (N, n_g) [N/m], ∂λ_n/∂ẇ or None, rows (n_g,) (−1: no normal row);
    at the penetration w − g − ½ Σ κ q² of a curved partner (:mod:`sarfe.hbm.laws.curvature`)."""
    rows = contacts.normal_row[idx]
    has = rows >= 0
    gap = contacts.gap[idx]
    r = hm.time_samples(R, N)
    w = np.where(has, r[:, np.maximum(rows, 0)], gap)
    kappa = curvature.curvatures(p)
    if kappa is not None:
        w = curvature.effective_normal(kappa, w, tangential_samples(contacts, idx, r))
    wdot = None
    if law.velocity_dependent:
        slope = hm.derivative_matrix((R.shape[0] - 1) // 2) @ R
        wdot = np.where(has, omega * hm.time_samples(slope, N)[:, np.maximum(rows, 0)], 0.0)
    out = law.normal(p, gap, w, wdot)
    stiffness = np.where(has, out.stiffness, 0.0)
    damping = None if out.damping is None else np.where(has, out.damping, 0.0)
    return out.force, stiffness, damping, rows


def _memory_block(s, omega, P_march, n_rho_march, drho, k_t, H, N):
    r"""δλ̃_t/δ(local harmonics) at exponent s (complex), (n, 2, 3P) per sample summed by E:
    returns (P, n, 2, 3P) complex, local layout h·3 + l; P_march, n_rho_march from
    :func:`_slider_march`."""
    return _memory_blocks(np.array([s], dtype=complex), omega, P_march, n_rho_march, drho, k_t,
                          H, N)[0]


def _memory_blocks(s, omega, P_march, n_rho_march, drho, k_t, H, N, chunk=2, setup=None):
    r""":func:`_memory_block` at several exponents s (n_s,): (n_s, P, n, 2, 3P) complex. The march
    is linear in the perturbation and s enters only through the factor e^{−sh} per sample, so the
    compiled march of :func:`sarfe.hbm.stability.march.linear_march` serves all s; its history
    ∂δw_j/∂δw_{−1} = e^{−sh(j+1)} Π_j (Π_j = P_j ⋯ P_0, s-independent), the periodic start
    δw_{−1} = (I − e^{−sT} Π_{N−1})⁻¹ δw_{N−1} where regular, and the harmonic coefficients taken
    by the DFT matrix E (2H+1, N): δλ̃ = k_t (E δq − E δw − (E ∂w/∂w₀) δw₀). ``chunk`` exponents
    are marched at a time (the samples of a chunk, (N, chunk, n, 2, 2, 3P), stay in cache: on the
    P1 door trim, N = 256, 4 sliding contacts, H = 15, 1.3 ms per s at chunk 2 against 2.0 ms at
    8, where the march wrote 24 MB per chunk);
    ``setup``: the s-independent arrays of :func:`_memory_setup` when already computed."""
    from sarfe.hbm.stability.march import linear_march   # numba (0.4 s to import): 2-D sliders only

    s = np.atleast_1d(np.asarray(s, dtype=complex))
    if setup is None:
        setup = _memory_setup(omega, P_march, n_rho_march, drho, H, N)
    stuck = setup["stuck"]
    n, P = stuck.size, 2 * H + 1
    out = np.empty((s.size, P, n, 2, 3 * P), complex)
    # a contact stuck all period (P_j = I, b_j = 0) keeps δw ≡ 0: δλ̃_t = k_t E δq at every s
    out[:, :, stuck] = k_t[stuck, None, None] * setup["Edq"][None, :, None]
    if np.all(stuck):
        return out
    moving = ~stuck
    step, source, products = (setup[k][:, moving] for k in ("step", "source", "products"))
    E, Edq, h, k_t, n = setup["E"], setup["Edq"], setup["h"], k_t[moving], int(moving.sum())
    for first in range(0, s.size, chunk):
        sc = s[first:first + chunk]
        m = sc.size
        march = linear_march(np.exp(-sc * h), step, source)                 # (N, m, n, 2, 2, 3P)
        last = march[-1, :, :, :, 0] + 1j * march[-1, :, :, :, 1]             # δw_{N−1} (m, n, 2, 3P)
        powers = np.exp(-sc[:, None] * h * np.arange(1, N + 1))                # e^{−sh(j+1)} (m, N)
        Eh = ((E[None] * powers[:, None, :]) @ products.reshape(N, -1)).reshape(m, P, n, 2, 2)
        system = np.eye(2) - powers[:, -1, None, None, None] * products[-1]    # (m, n, 2, 2)
        regular = np.abs(np.linalg.det(system)) > 1e-9
        dw0 = np.zeros((m, n, 2, 3 * P), complex)
        if np.any(regular):
            dw0[regular] = np.linalg.solve(system[regular], last[regular])
        Edw = (E @ march.reshape(N, -1)).reshape(P, m, n, 2, 2, 3 * P)       # one real GEMM
        Edw = np.moveaxis(Edw[..., 0, :] + 1j * Edw[..., 1, :], 1, 0)          # (m, P, n, 2, 3P)
        coeff = Edq[None, :, None] - Edw - Eh @ dw0[:, None]
        out[first:first + chunk, :, moving] = k_t[None, None, :, None, None] * coeff
    return out


def _memory_setup(omega, P_march, n_rho_march, drho, H, N, drho_q=None):
    """The s-independent arrays of :func:`_memory_blocks` (once per solution): step P_j
    (N, n, 2, 2), source b_j = (I − P_j) δq_j + n_j dρ_j (N, n, 2, 3P) with
    dρ_j = ∂ρ/∂w δn_j (+ ∂ρ/∂q δq_j, ``drho_q`` (N, n, 2), for a curved partner), products Π_j
    (N, n, 2, 2), the DFT matrix E (2H+1, N), E δq (2H+1, 2, 3P), sample spacing h [s], and
    ``stuck`` (n,): contacts stuck at every sample (P_j = I, b_j = 0: no march needed)."""
    from sarfe.hbm.stability.march import step_products   # numba (0.4 s to import): 2-D sliders only

    P = 2 * H + 1
    E, Phi = hm.fourier_matrices(H, N)
    dq = np.zeros((N, 2, 3 * P))
    dq[:, 0, 1::3], dq[:, 1, 2::3] = Phi, Phi
    dn = np.zeros((N, 3 * P))
    dn[:, 0::3] = Phi
    step = np.ascontiguousarray(P_march, dtype=float)
    source = (dq[:, None] - np.einsum("jcab,jbx->jcax", step, dq)
              + n_rho_march[..., None] * (drho[:, :, None, None] * dn[:, None, None, :]))
    if drho_q is not None:
        slide = np.einsum("jca,jax->jcx", drho_q, dq)                        # ∂ρ/∂q δq_j
        source = source + n_rho_march[..., None] * slide[:, :, None, :]
    stuck = np.all(step == np.eye(2), axis=(0, 2, 3)) & np.all(source == 0.0, axis=(0, 2, 3))
    return dict(step=step, source=source, products=step_products(step), E=E,
                Edq=np.einsum("hj,jcx->hcx", E, dq), h=2.0 * np.pi / (omega * N), stuck=stuck)


def _slider_march(q, rho, start, one_d=False):
    """The slider states of one period marched from ``start``: ∂w_j/∂w_{j−1} = P_j (N, n, 2, 2)
    and ∂w_j/∂ρ_j = n_j (N, n, 2). They do not depend on s: computed once per solution.

    ``one_d`` (every slider has one tangent direction): the states w_j come from the clamp scan of
    :func:`sarfe.hbm.laws.jenkins.jenkins_periodic_1d` (the march from the periodic state that
    ``start`` is clamped to, without a sample loop), and P_j, n_j from one vectorized return map."""
    N, n = q.shape[0], q.shape[1]
    if one_d:
        periodic = jenkins_periodic_1d(q[:, :, 0], rho, np.asarray(start, dtype=float)[:, 0])
        previous = np.zeros((N, n, 2))
        previous[0, :, 0] = periodic["slider_end"]
        previous[1:, :, 0] = periodic["slider"][:-1]
        _, _, P, n_rho = slider_update_derivatives(previous, q, rho)
        return P, n_rho
    from sarfe.hbm.stability.march import slider_steps   # the 2-D return map is a march: compiled

    return slider_steps(np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(rho, dtype=float),
                        np.ascontiguousarray(start, dtype=float))


def _memory_block_1d(s, omega, P, n_rho, drho, k_t, H, N):
    r""":func:`_memory_block` for sliders with one tangent direction, without a sample loop.

    In 1-D the linearized return map has P_j ∈ {0, 1} (slip or separation: 0, the history is
    reset; stick: 1), so ŵ_i = e^{−s h d(i)} b_{j(i)}, b_j = p̂_j + n_j dρ_j ŵ_n,j, with j(i) the
    last reset sample at or before i (cyclic, :func:`last_reset_index`) and d(i) = (i − j(i)) mod N
    — the periodic solution of the march; ŵ = 0 for a contact that never resets (regular where
    e^{−sT} ≠ 1). Only the first tangent row is filled (the second is absent for these contacts)."""
    return _memory_blocks_1d(np.array([s], dtype=complex), omega, P, n_rho, drho, k_t, H, N)[0]


def _memory_blocks_1d(s, omega, P, n_rho, drho, k_t, H, N, drho_q=None):
    """:func:`_memory_block_1d` at several exponents s (n_s,): (n_s, P, n, 2, 3P) complex;
    ``drho_q`` (N, n, 2): ∂ρ/∂q of a curved partner (b_j gains n_j ∂ρ/∂q p̂_j)."""
    s = np.atleast_1d(np.asarray(s, dtype=complex))
    P_count = 2 * H + 1
    Phi = hm.fourier_matrices(H, N)[1]
    reset = P[:, :, 0, 0] == 0.0
    j, has = last_reset_index(reset)
    distance = (np.arange(N)[:, None] - j) % N
    weight = (np.exp(-s[:, None, None] * 2.0 * np.pi / (omega * N) * distance[None])
              * has[None, None, :])                                                  # (n_s, N, n)
    gathered = Phi[j]                                                                # (N, n, P)
    slope = np.take_along_axis(n_rho[:, :, 0] * drho, j, axis=0)                    # n_j dρ_j
    n = P.shape[1]
    dforce = np.zeros((N, s.size, n, 2, 3 * P_count), complex)
    weight = np.moveaxis(weight, 0, 1)                                               # (N, n_s, n)
    dforce[:, :, :, 0, 1::3] = k_t[None, None, :, None] * (Phi[:, None, None, :]
                                                           - weight[..., None] * gathered[:, None])
    dforce[:, :, :, 0, 0::3] = -k_t[None, None, :, None] * (weight * slope[:, None])[..., None] \
        * gathered[:, None]
    if drho_q is not None:
        slide = np.take_along_axis(n_rho[:, :, 0] * drho_q[:, :, 0], j, axis=0)
        dforce[:, :, :, 0, 1::3] -= k_t[None, None, :, None] \
            * (weight * slide[:, None])[..., None] * gathered[:, None]
    coeff = hm.harmonic_coefficients(dforce.real, H) + 1j * hm.harmonic_coefficients(dforce.imag, H)
    return np.moveaxis(coeff, 1, 0)


class ContactOperator:
    r"""s ↦ (I⊗G)ᵀ [𝒥(s) − 𝒥_AFT] (I⊗G) on all DOFs (sparse, complex): the correction of the Newton
    Jacobian ∂R/∂ũ that turns it into Hill's operator at exponent s (module docstring).

    problem: :class:`sarfe.hbm.residual.Problem` (all harmonic rows); U (2H+1, n) [m]; omega
    [rad/s]; forces: the :class:`ContactForces` of the AFT at U (its blocks and slider state).
    ``has_memory``: some contact has a Jenkins element (the correction depends on s);
    ``refine``: oversampling of the normal parts.
    """

    def __init__(self, problem, U, omega, forces, refine=1):
        contacts, H, N = problem.contacts, problem.harmonics, problem.samples_per_period
        G = contacts.gap_map
        self.H, self.omega = H, float(omega)
        self.n_rows = G.shape[0]
        self.GG = sp.kron(sp.identity(2 * H + 1), G, format="csr")
        R = np.asarray(G @ np.asarray(U).T).T
        r = hm.time_samples(R, N)
        fine = max(int(refine), 1) * N
        self.static, self.memory = [], []
        for law, idx, p in laws.groups(contacts):
            _, stiffness, damping, rows = _normal_part(law, p, contacts, idx, R, omega, fine)
            block = pointwise_jacobian(stiffness, H)
            if damping is not None:
                block = block + omega * pointwise_jacobian(damping, H) @ hm.derivative_matrix(H)
            with_tangent = contacts.tangent_rows[idx, 0] >= 0 if law.tangent is not None \
                else np.zeros(idx.size, bool)
            alone = ~with_tangent
            if np.any(alone):
                self.static.append((rows[alone, None], block[alone]))
            if not np.any(with_tangent):
                continue
            sel = np.flatnonzero(with_tangent)
            t_idx = idx[sel]
            t_rows = contacts.tangent_rows[t_idx]
            present = t_rows >= 0
            q = np.where(present[None], r[:, np.maximum(t_rows, 0)], 0.0)
            force_n, stiff_n, _, _ = _normal_part(law, {k: v[sel] for k, v in p.items()},
                                                 contacts, t_idx, R, omega, N)
            k_t = p["tangential_stiffness"][sel]
            mu = p["friction_coefficient"][sel]
            start = np.nan_to_num(forces.slider_end[t_idx])
            normal = np.zeros((sel.size, 3 * (2 * H + 1), 3 * (2 * H + 1)))
            normal[:, 0::3, 0::3] = block[sel]
            kappa = curvature.curvatures({k: v[sel] for k, v in p.items()})
            drho_q = None
            if kappa is not None:     # curved partner: pointwise couplings, ρ moves with q too
                normal += curvature_blocks(kappa, q, force_n, stiff_n, H)
                drho_q = (mu / k_t)[:, None] * curvature.coupling(kappa, q, force_n, stiff_n)[1]
            one_d = bool(np.all(t_rows[:, 1] < 0))
            march = _slider_march(q, mu * force_n / k_t, start, one_d)
            self.memory.append(dict(rows=np.column_stack([rows[sel], t_rows]), normal=normal,
                                    march=march, drho=mu * stiff_n / k_t, k_t=k_t, N=N,
                                    one_d=one_d, drho_q=drho_q))
        self.has_memory = bool(self.memory)
        base = jacobian_matrix(forces.blocks, self.n_rows, H)
        self._fixed = jacobian_matrix(self.static, self.n_rows, H) - base
        self._dense_parts = None        # (I⊗G, fixed part) as ndarrays, on first dense_correction

    @property
    def pointwise_correction(self):
        """𝒥 − 𝒥_AFT of the contacts without memory (s-independent; sparse, real)."""
        return self._fixed

    def blocks_at(self, s):
        """The tangent-group blocks (rows, 𝒥(s)) — complex — for jacobian_matrix."""
        return [(rows, J[0]) for rows, J in self.blocks_at_many(np.array([s], dtype=complex))]

    def memory_coefficients(self, s):
        """The s-dependent tangent rows of each memory group at exponents s (n_s,):
        [(rows (n_g, 3), δλ̃_t (n_s, P, n_g, 2, 3P))] — row harmonic, contact, tangent direction,
        local column h·3 + l (l = 0 normal, 1, 2 tangents); the normal rows of the groups are
        s-independent (``g["normal"]``)."""
        s = np.atleast_1d(np.asarray(s, dtype=complex))
        out = []
        for g in self.memory:
            args = (s, self.omega, *g["march"], g["drho"], g["k_t"], self.H, g["N"])
            if g["one_d"]:
                out.append((g["rows"], _memory_blocks_1d(*args, drho_q=g["drho_q"])))
                continue
            if "setup" not in g:         # the s-independent part, once per solution
                g["setup"] = _memory_setup(self.omega, *g["march"], g["drho"], self.H, g["N"],
                                           g["drho_q"])
            out.append((g["rows"], _memory_blocks(*args, setup=g["setup"])))
        return out

    def blocks_at_many(self, s):
        """:meth:`blocks_at` at several exponents s (n_s,): [(rows, 𝒥 (n_s, n_g, 3P, 3P))]."""
        s = np.atleast_1d(np.asarray(s, dtype=complex))
        out = []
        for g, (rows, coeff) in zip(self.memory, self.memory_coefficients(s)):
            J = np.broadcast_to(g["normal"], (s.size,) + g["normal"].shape).astype(complex)
            J[:, :, 1::3, :] = np.moveaxis(coeff[:, :, :, 0, :], 1, 2)
            J[:, :, 2::3, :] = np.moveaxis(coeff[:, :, :, 1, :], 1, 2)
            if g["drho_q"] is not None:          # the normal force's tangential components
                J[:, :, 1::3, :] += g["normal"][:, 1::3, :]
                J[:, :, 2::3, :] += g["normal"][:, 2::3, :]
            out.append((rows, J))
        return out

    def rows_correction(self, s):
        """𝒥(s) − 𝒥_AFT on the contact rows ((2H+1) n_rows square, sparse, harmonic-major)."""
        J = self._fixed.astype(complex)
        for rows, block in self.blocks_at(s):
            J = J + jacobian_matrix([(rows, block.real)], self.n_rows, self.H) \
                + 1j * jacobian_matrix([(rows, block.imag)], self.n_rows, self.H)
        return J.tocsr()

    def correction(self, s):
        """(I⊗G)ᵀ [𝒥(s) − 𝒥_AFT] (I⊗G) (sparse CSR, complex when s is)."""
        return (self.GG.T @ self.rows_correction(s) @ self.GG).tocsr()

    def dense_correction(self, s):
        """:meth:`correction` as a dense ndarray (complex), for small models: (I⊗G) and the
        s-independent part are densified once, the memory blocks scattered densely, so the
        refinement's many evaluations build no scipy.sparse matrix."""
        if self._dense_parts is None:
            self._dense_parts = (self.GG.toarray(), self._fixed.toarray())
        GG, fixed = self._dense_parts
        J = fixed.astype(complex)
        for rows, block in self.blocks_at(s):
            J += jacobian_matrix([(rows, block.real)], self.n_rows, self.H, dense=True)
            J += 1j * jacobian_matrix([(rows, block.imag)], self.n_rows, self.H, dense=True)
        return GG.T @ J @ GG
