"""sarfe.hbm — harmonic balance of a linear model with squeak (friction) and rattle (impact) contacts.

    R(ũ, ω) = S(ω) ũ + f̃_nl(ũ) − f̃_e = 0,    f̃_nl = Gᵀ λ̃(G ũ)  (AFT, analytic Jacobian)

Modules: harmonics (Fourier convention), contacts (ContactSet), unilateral / friction (laws),
aft (forces + Jacobian), linear (S(ω), condensation), residual, newton, solve (one ω),
continuation (pseudo-arclength in ω), stability (Hill), solution (options + result).
"""
from .contacts import ContactSet, make_contact_set
from .continuation import continuation
from .model import LinearModel, make_linear_model
from .solution import ContinuationOptions, HarmonicSolution, SolverOptions
from .solve import solve_frequency
from .stability import floquet_exponents, hill_stability

__all__ = [
    "LinearModel", "make_linear_model", "ContactSet", "make_contact_set", "SolverOptions",
    "ContinuationOptions", "HarmonicSolution", "solve_frequency", "continuation",
    "hill_stability", "floquet_exponents",
]
