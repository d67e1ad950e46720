"""ADAPTERS to the other parts of sarfe (mesh loading, generators, HBM engine).

The case layer calls the engine through these few functions so that a missing or renamed piece
fails with one clear message. ``solve_point`` / ``sweep`` fall back to the time integrator
(:func:`sarfe.hbm.time_integration.integrate_time`, periodic steady state) only when the
harmonic-balance engine (``sarfe.hbm.solve_frequency`` / ``continuation``) is not installed.
"""
from __future__ import annotations

import dataclasses
import importlib
from types import SimpleNamespace

import numpy as np

from sarfe.io.errors import CaseError


# --------------------------------------------------------------------------------------- meshes
def load_mesh_file(path, length_unit):
    """sarfe.mesh.load_mesh(path, length_unit=...) → PanelMesh."""
    try:
        from sarfe.mesh import load_mesh
    except ImportError:  # the mesh part may expose it from a submodule only
        try:
            from sarfe.mesh.io import load_mesh  # type: ignore
        except ImportError:
            raise CaseError("mesh reading is not available (sarfe.mesh.load_mesh missing)") from None
    return load_mesh(path, length_unit=length_unit)


def generate_mesh(name, mesh_size, params):
    """sarfe.mesh.generators.<name>.generate(mesh_size=..., **params) → PanelMesh."""
    try:
        module = importlib.import_module(f"sarfe.mesh.generators.{name}")
    except ImportError as exc:
        raise CaseError(f"mesh generator '{name}' is not available ({exc})") from None
    return module.generate(mesh_size=mesh_size, **params)


# ------------------------------------------------------------------------------------ HBM engine
def hbm_engine():
    """(solve_frequency, continuation, SolverOptions, ContinuationOptions) or None if not there."""
    try:
        hbm = importlib.import_module("sarfe.hbm")
        return (hbm.solve_frequency, hbm.continuation, getattr(hbm, "SolverOptions", None),
                getattr(hbm, "ContinuationOptions", None))
    except (ImportError, AttributeError):
        return None


def make_options(cls, values: dict):
    """Instantiate an options dataclass with the entries of ``values`` it has fields for."""
    if cls is None:
        return None
    names = {f.name for f in dataclasses.fields(cls)}
    return cls(**{k: v for k, v in values.items() if k in names and v is not None})


def time_integration_point(model, contacts, excitation, omega, harmonics, samples_per_period,
                           initial=None, max_periods=400):
    """A HarmonicSolution look-alike from time integration (fallback when no HBM engine, and the
    start guess of a retry: then ``max_periods`` is small and the state need not be steady)."""
    from sarfe.hbm.harmonics import harmonic_coefficients
    from sarfe.hbm.time_integration import integrate_time

    steps = max(int(samples_per_period), 256)
    response = integrate_time(model, contacts, excitation, omega, harmonics,
                              steps_per_period=steps, max_periods=max_periods, initial=initial)
    return SimpleNamespace(
        omega=float(omega), harmonics=int(harmonics), samples_per_period=steps,
        displacement=response.displacement_harmonics,
        contact_displacement=harmonic_coefficients(response.contact_displacement, harmonics),
        contact_force=response.contact_force_harmonics,
        contact_force_time=response.contact_force,
        contact_state=response.contact_state,
        converged=bool(response.steady),
        reason="time integration reached a periodic state" if response.steady
        else "time integration did not reach a periodic state",
        iterations=int(response.periods), residual_norm=float(response.periodicity_error),
        friction_passes=0, stable=None, floquet_exponent=float("nan"))


def contact_displacement_samples(solution, gap_map, samples):
    """r(θ_j) (N, n_rows) of a solution (time samples of its contact-displacement harmonics)."""
    from sarfe.hbm.harmonics import time_samples

    R = getattr(solution, "contact_displacement", None)
    if R is None:
        R = np.asarray(solution.displacement) @ gap_map.T.toarray() if gap_map.shape[0] else None
    return time_samples(np.asarray(R), samples)


# ------------------------------------------------------------------ ADAPTER: pyFFTW issue #344
class _FftOnMatrices:
    """ADAPTER for pyFFTW issue #344 (github.com/pyFFTW/pyFFTW/issues/344): a real FFT along axis 0
    of an array with two or more further axes can fail with "The data has an uncaught error that
    led to the planner returning NULL". It sometimes fails for the 4-D Jacobian samples of 2-D
    friction in ``sarfe.hbm.aft``. This shim folds the trailing axes into one before calling the
    same backend, so only 1-D and 2-D transforms reach pyFFTW; the numbers are identical. Remove it
    once ``sarfe.hbm.harmonics`` reshapes by itself.
    """

    def __init__(self, backend):
        self.backend = backend

    def rfft(self, u, axis=0, **kwargs):
        u = np.asarray(u)
        if axis != 0 or u.ndim <= 2:
            return self.backend.rfft(u, axis=axis, **kwargs)
        out = self.backend.rfft(u.reshape(u.shape[0], -1), axis=0, **kwargs)
        return out.reshape((out.shape[0],) + u.shape[1:])

    def irfft(self, spectrum, n=None, axis=0, **kwargs):
        spectrum = np.asarray(spectrum)
        if axis != 0 or spectrum.ndim <= 2:
            return self.backend.irfft(spectrum, n=n, axis=axis, **kwargs)
        out = self.backend.irfft(spectrum.reshape(spectrum.shape[0], -1), n=n, axis=0, **kwargs)
        return out.reshape((out.shape[0],) + spectrum.shape[1:])

    def __getattr__(self, name):
        return getattr(self.backend, name)


def guard_fft_backend():
    """Install :class:`_FftOnMatrices` around ``sarfe.hbm.harmonics._fft`` (once, pyFFTW only)."""
    try:
        from sarfe.hbm import harmonics
    except ImportError:
        return
    backend = getattr(harmonics, "_fft", None)
    if backend is not None and getattr(harmonics, "FFT_BACKEND", "") == "pyfftw" and not isinstance(
            backend, _FftOnMatrices):
        harmonics._fft = _FftOnMatrices(backend)
