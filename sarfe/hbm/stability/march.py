r"""Compiled linearized slider march of 2-D Jenkins elements at many Floquet exponents (numba):
the sample loop of :func:`sarfe.hbm.stability.contact_terms._memory_blocks`.

A perturbation e^{st} of the orbit reaches the slider of sample j through the return map
(:mod:`sarfe.hbm.stability.contact_terms`, item 1), h = T/N the sample spacing:

    δw_j = P_j (e^{−sh} δw_{j−1}) + b_j,      δw_{−1} = 0,

with the s-independent step derivative P_j (n, 2, 2) and source b_j (n, 2, C) of the orbit; s
enters only through the scalar factor e^{−sh}, so one compiled loop serves every exponent of a
contour. The 2-D return map does not compose in closed form (the 1-D clamp does:
:func:`sarfe.hbm.stability.contact_terms._memory_blocks_1d`), hence the sequential loop, here over
exponents × contacts × samples × columns without Python overhead per sample. Compiled on first
use and cached on disk (``cache=True``).

Array shapes: N samples, n contacts, m exponents, C = 3P local harmonic columns.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from sarfe.hbm.laws.jenkins_march import return_map_derivative, return_map_step


@njit(cache=True)
def linear_march(decay, step, source):
    r"""δw_j of the linearized march δw_j = P_j (d δw_{j−1}) + b_j from δw_{−1} = 0, for every
    factor d = e^{−sh} of ``decay`` (m,) complex; ``step`` P_j (N, n, 2, 2) [-], ``source`` b_j
    (N, n, 2, C) real [m per unit column]. Returns (N, m, n, 2, 2, C) float: [..., 0, :] the real,
    [..., 1, :] the imaginary part of δw_j (split so that the column loop runs on real arrays)."""
    N, n, _, C = source.shape
    m = decay.shape[0]
    out = np.empty((N, m, n, 2, 2, C))
    a0, b0 = np.empty(C), np.empty(C)         # δw component 0: real, imaginary
    a1, b1 = np.empty(C), np.empty(C)         # component 1
    for k in range(m):
        dr, di = decay[k].real, decay[k].imag
        for c in range(n):
            a0[:] = 0.0
            b0[:] = 0.0
            a1[:] = 0.0
            b1[:] = 0.0
            for j in range(N):
                p00, p01, p10, p11 = step[j, c, 0, 0], step[j, c, 0, 1], step[j, c, 1, 0], step[j, c, 1, 1]
                for col in range(C):
                    # z = d x (complex), then y = P z + b
                    z0r = dr * a0[col] - di * b0[col]
                    z0i = dr * b0[col] + di * a0[col]
                    z1r = dr * a1[col] - di * b1[col]
                    z1i = dr * b1[col] + di * a1[col]
                    a0[col] = p00 * z0r + p01 * z1r + source[j, c, 0, col]
                    b0[col] = p00 * z0i + p01 * z1i
                    a1[col] = p10 * z0r + p11 * z1r + source[j, c, 1, col]
                    b1[col] = p10 * z0i + p11 * z1i
                out[j, k, c, 0, 0, :] = a0
                out[j, k, c, 0, 1, :] = b0
                out[j, k, c, 1, 0, :] = a1
                out[j, k, c, 1, 1, :] = b1
    return out


@njit(cache=True)
def step_products(step):
    """Π_j = P_j P_{j−1} ⋯ P_0 (N, n, 2, 2) [-] of the step derivatives P (N, n, 2, 2): the history
    ∂δw_j/∂δw_{−1} of the march at s = 0 (at s it is e^{−s h (j+1)} Π_j)."""
    N, n = step.shape[0], step.shape[1]
    out = np.empty((N, n, 2, 2))
    for c in range(n):
        h00, h01, h10, h11 = 1.0, 0.0, 0.0, 1.0
        for j in range(N):
            p00, p01, p10, p11 = step[j, c, 0, 0], step[j, c, 0, 1], step[j, c, 1, 0], step[j, c, 1, 1]
            h00, h01, h10, h11 = (p00 * h00 + p01 * h10, p00 * h01 + p01 * h11,
                                  p10 * h00 + p11 * h10, p10 * h01 + p11 * h11)
            out[j, c, 0, 0], out[j, c, 0, 1], out[j, c, 1, 0], out[j, c, 1, 1] = h00, h01, h10, h11
    return out


@njit(cache=True)
def slider_steps(q, rho, start):
    r"""The return-map derivatives of one period of 2-D sliders marched from ``start`` (n, 2) [m]:
    P_j = ∂w_j/∂w_{j−1} (N, n, 2, 2) [-] and n_j = ∂w_j/∂ρ_j (N, n, 2) [-] (the disk projection
    of :mod:`sarfe.hbm.laws.jenkins_march`: (ρ/|t|)(I − n nᵀ) in slip, I in stick, 0 separated).
    q (N, n, 2) [m] tangential displacements, rho (N, n) [m] slip radii."""
    N, n = rho.shape
    step = np.empty((N, n, 2, 2))
    slope = np.empty((N, n, 2))
    for c in range(n):
        x0, x1 = start[c, 0], start[c, 1]
        for j in range(N):
            x0, x1, ratio, slipping, u0, u1, separated = return_map_step(
                x0, x1, q[j, c, 0], q[j, c, 1], rho[j, c])
            p00, p01, p10, p11, s0, s1 = return_map_derivative(ratio, slipping, u0, u1, separated)
            step[j, c, 0, 0], step[j, c, 0, 1], step[j, c, 1, 0], step[j, c, 1, 1] = p00, p01, p10, p11
            slope[j, c, 0], slope[j, c, 1] = s0, s1
    return step, slope
