"""sarfe.hbm — harmonic balance of a linear model with squeak (friction) and rattle (impact) contacts.

    R(ũ, ω) = S(ω) ũ + f̃_nl(ũ) − f̃_e = 0,    f̃_nl = Gᵀ λ̃(G ũ)  (AFT, analytic Jacobian)

Modules: harmonics (Fourier convention), contacts (ContactSet), laws (one module per contact law
and its registration: rattle, squeak, damped_impact, tabulated, the Jenkins element), aft (forces +
Jacobian), linear (S(ω), condensation), residual, newton, solve (one ω), continuation
(pseudo-arclength in ω), stability (Hill), solution (options + result), harmonic_set (solve a
subset of the orders, e.g. odd only, ``harmonic_set='odd' | 'auto'``).

Example (NLvib example 03)::

    K = np.array([[1.0, -1.0], [-1.0, 2.0]])
    model = make_linear_model(np.eye(2), 0.03 * K, K)
    contacts = make_contact_set(sp.csr_matrix([[1.0, 0.0]]), ["rattle"], [0], [[-1, -1]],
                                gap=1.0, normal_stiffness=100.0)
    H, N = 21, 1024
    force = np.zeros((2 * H + 1, 2)); force[1, 1] = 0.1          # 0.1 cos Ωt on DOF 2
    branch = continuation(model, contacts, force, 0.5, 0.8, H, N)  # through the folds
    peak = max(s.amplitude(1) for s in branch)                     # ≈ 0.9374 at Ω ≈ 0.751
"""
from sarfe.hbm.contacts import ContactSet, make_contact_set
from sarfe.hbm.continuation import continuation
from sarfe.hbm.model import LinearModel, make_linear_model
from sarfe.hbm.solution import ContinuationOptions, HarmonicSolution, SolverOptions
from sarfe.hbm.solve import solve_frequency
from sarfe.hbm.stability.hill import floquet_exponents, hill_stability

__all__ = [
    "LinearModel", "make_linear_model", "ContactSet", "make_contact_set", "SolverOptions",
    "ContinuationOptions", "HarmonicSolution", "solve_frequency", "continuation",
    "hill_stability", "floquet_exponents",
]
