r"""Fourier convention of sarfe's harmonic balance, and the time/frequency transforms of the AFT.

Convention (used everywhere in sarfe)
-------------------------------------
A periodic quantity with period T = 2π/ω is written with the phase θ = ωt as

    u(θ) = u0 + Σ_{k=1..H} ( u_kc cos kθ + u_ks sin kθ ).

Its harmonic coefficients are stored *harmonic-major* in an array ``U`` of shape ``(2H+1, ...)``:

    U[0] = u0          (the constant term, stored as is — not halved, not scaled by √2)
    U[2k-1] = u_kc     (cosine of harmonic k)
    U[2k]   = u_ks     (sine of harmonic k)

so a vector of unknowns for n DOFs is ``U.ravel()`` = [u0 (n), u1c (n), u1s (n), …, uHc (n), uHs (n)].
The AFT samples one period at θ_j = 2π j / N, j = 0 … N-1; time samples are stored as ``(N, ...)``.
N ≥ 2H+1 is required; N ≥ 4H+1 avoids aliasing of a cubic term, and nonsmooth contact laws need far
more (their coefficients decay only like k⁻²).

Velocities: u̇ = ω ∂u/∂θ, with (∂u/∂θ)_kc = k u_ks and (∂u/∂θ)_ks = −k u_kc (see
:func:`derivative_matrix`).
"""
from __future__ import annotations

import warnings

import numpy as np

# numpy.fft (pocketfft): as fast as pyFFTW's cached interfaces at the AFT's sizes (measured rfft of
# N = 256 / 1024 / 4096 samples × 1–4 columns: 12 / 20–33 / 75 µs vs pyFFTW 20 / 22–40 / 61 µs) and
# nothing to import — pyfftw.interfaces imports dask.array, 0.24 s of every run's start.
import numpy.fft as _fft

FFT_BACKEND = "numpy"

__all__ = [
    "check_harmonics",
    "time_samples",
    "harmonic_coefficients",
    "derivative_matrix",
    "fourier_matrices",
    "harmonic_orders",
    "FFT_BACKEND",
]


def check_harmonics(harmonics, samples_per_period) -> None:
    """Validate H and N: H ≥ 1 integer, N ≥ 2H+1 (error), warn when N < 4H+1.

    Raises ValueError naming the parameter.
    """
    if isinstance(harmonics, bool) or not isinstance(harmonics, (int, np.integer)) or harmonics < 1:
        raise ValueError(f"harmonics H must be an integer >= 1, got {harmonics!r}")
    if (
        isinstance(samples_per_period, bool)
        or not isinstance(samples_per_period, (int, np.integer))
        or samples_per_period < 2 * harmonics + 1
    ):
        raise ValueError(
            f"samples_per_period N must be an integer >= 2H+1 = {2 * harmonics + 1} "
            f"for H = {harmonics}, got {samples_per_period!r}"
        )
    if samples_per_period < 4 * harmonics + 1:
        warnings.warn(
            f"samples_per_period N = {samples_per_period} < 4H+1 = {4 * harmonics + 1}: "
            "nonlinear contact forces will alias; use N >= 4H+1 (contact laws need more)",
            stacklevel=2,
        )


def harmonic_orders(harmonics: int) -> np.ndarray:
    """Harmonic order k of each coefficient row: [0, 1, 1, 2, 2, …, H, H] (shape (2H+1,))."""
    return np.concatenate(([0], np.repeat(np.arange(1, harmonics + 1), 2)))


def time_samples(U: np.ndarray, samples_per_period: int) -> np.ndarray:
    """Inverse transform: coefficients ``U`` (2H+1, ...) → samples u(θ_j) of shape (N, ...).

    u(θ_j) = U[0] + Σ_k U[2k-1] cos kθ_j + U[2k] sin kθ_j, θ_j = 2πj/N.
    """
    U = np.asarray(U, dtype=float)
    H = (U.shape[0] - 1) // 2
    N = int(samples_per_period)
    spectrum = np.zeros((N // 2 + 1,) + U.shape[1:], dtype=complex)
    spectrum[0] = N * U[0]
    spectrum[1 : H + 1] = 0.5 * N * (U[1::2] - 1j * U[2::2])
    # transform along axis 0 of a 2-D view: pyFFTW's planner can return NULL for axis 0 of
    # arrays with several trailing axes (pyFFTW issue #344); folding them is exact.
    flat = _fft.irfft(spectrum.reshape(spectrum.shape[0], -1), n=N, axis=0)
    return flat.reshape((N,) + U.shape[1:])


def harmonic_coefficients(u: np.ndarray, harmonics: int) -> np.ndarray:
    """Forward transform: samples ``u`` (N, ...) over one period → coefficients (2H+1, ...).

    u0 = (1/N) Σ_j u_j,  u_kc = (2/N) Σ_j u_j cos kθ_j,  u_ks = (2/N) Σ_j u_j sin kθ_j.
    """
    u = np.asarray(u, dtype=float)
    N = u.shape[0]
    H = int(harmonics)
    spectrum = _fft.rfft(u.reshape(N, -1), axis=0).reshape((N // 2 + 1,) + u.shape[1:])
    U = np.empty((2 * H + 1,) + u.shape[1:])
    U[0] = spectrum[0].real / N
    U[1::2] = 2.0 / N * spectrum[1 : H + 1].real
    U[2::2] = -2.0 / N * spectrum[1 : H + 1].imag
    return U


def derivative_matrix(harmonics: int) -> np.ndarray:
    """Matrix ∇ (2H+1, 2H+1) with ∂U/∂θ = ∇ U; velocity coefficients are ω ∇ U.

    Block k: [[0, k], [−k, 0]] acting on (u_kc, u_ks).
    """
    H = int(harmonics)
    nabla = np.zeros((2 * H + 1, 2 * H + 1))
    k = np.arange(1, H + 1)
    nabla[2 * k - 1, 2 * k] = k
    nabla[2 * k, 2 * k - 1] = -k
    return nabla


def fourier_matrices(harmonics: int, samples_per_period: int) -> tuple[np.ndarray, np.ndarray]:
    """Dense DFT pair (E, Φ): U = E u with E (2H+1, N) and u = Φ U with Φ (N, 2H+1).

    For small problems and tests; the solver path uses the FFTs above.
    """
    H, N = int(harmonics), int(samples_per_period)
    theta = 2.0 * np.pi * np.arange(N) / N
    k = np.arange(1, H + 1)
    Phi = np.empty((N, 2 * H + 1))
    Phi[:, 0] = 1.0
    Phi[:, 1::2] = np.cos(np.outer(theta, k))
    Phi[:, 2::2] = np.sin(np.outer(theta, k))
    E = Phi.T * (2.0 / N)
    E[0] = 1.0 / N
    return E, Phi
