"""sarfe.hbm — harmonic balance of a linear model with squeak (friction) and rattle (impact) contacts.

    R(ũ, ω) = S(ω) ũ + f̃_nl(ũ) − f̃_e = 0,    f̃_nl = Gᵀ λ̃(G ũ)  (AFT, analytic Jacobian)

Modules (in the order a solve uses them):
    harmonics          the Fourier convention (cos/sin rows, 2H+1 of them), time ↔ harmonics, ∇
    model              LinearModel: M, D, K on the kept DOFs
    modal              the model's modal basis (Vᵀ K V = I, diagonal damping) for the compliance
    dynamic_stiffness  S(ω) per harmonic, dynamic compliance condensation to the contact rows,
                       recovery of all DOFs (S(ω) Û = F̃)
    contacts           ContactSet: the gap map G (rows of all contacts) and each contact's law
    laws/              one module per contact law and its registration (rattle, squeak,
                       damped_impact, tabulated); jenkins, jenkins_march: the friction element and
                       its compiled 2-D march; contract: what a law provides
    aft                alternating frequency–time: contact force harmonics λ̃(r̃) and ∂λ̃/∂r̃
    residual           R(ũ, ω) and its Jacobian, full or condensed to the contact rows
    newton             damped Newton with line search (and chord steps at fixed ω)
    harmonic_set       solving a subset of the orders (odd only, 'auto') and the dropped content η
    solution           SolverOptions, ContinuationOptions, HarmonicSolution (the result)
    solve              one ω: first guess, homotopies, Newton, polish, finalize (solve_frequency)
    continuation       the sweep: pseudo-arclength continuation in ω through folds
    arclength          its steps: bordered tangent, hyperplane/sphere corrector, corner step
    energy_balance     is a point's energy balance resolved by its N samples (the sweep raises N)
    sampled_folds      turns of ω the AFT sampling makes: the sweep steps over them at fixed ω
    stability/         is the orbit stable? one entry, stability(...) (Hill, contact-row count, …)
    pruning            contact screening: contacts that never switch solved linearly
    linear_points      points where every contact stays open/closed/stuck: the linearized
                       response, checked by the laws' AFT (no Newton, no Hill)
    newmark            the Newmark march with contacts (the time integrator's step and periods)
    time_integration   periodic steady state by time integration: the HBM's independent check

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
