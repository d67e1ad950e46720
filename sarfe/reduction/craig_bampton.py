r"""Craig–Bampton reduction of (K, M) to boundary DOFs + fixed-interface modes.

Partition the free DOFs into boundary b (kept physically: contact, excitation, response points)
and interior i. With u_b = q_b and

    u_i = Ψ q_b + Φ q_m,     Ψ = −K_ii⁻¹ K_ib  (constraint modes, static condensation),
                             K_ii Φ = M_ii Φ Ω²,  Φᵀ M_ii Φ = I  (fixed-interface normal modes),

the transformation u = T q, T = [[I, 0], [Ψ, Φ]], gives K_r = Tᵀ K T and M_r = Tᵀ M T:

    K_r = [[K_bb + K_bi Ψ, 0], [0, Ω²]]
    M_r = [[M_bb + M_bi Ψ + Ψᵀ M_ib + Ψᵀ M_ii Ψ, (M_bi + Ψᵀ M_ii) Φ], [sym, I]]

K_ii is factorized once (``sarfe.linalg.factorize``) and that factor serves Ψ
(one block solve with n_b right-hand sides) and the shift-invert iteration for Φ
(:func:`sarfe.reduction.fixed_interface_modes.fixed_interface_modes`: by default a block Lanczos
on K_ii⁻¹ M_ii whose steps are multi-RHS solves, capped and continued by spectrum slicing when
many modes are wanted; alternatively ARPACK). This module holds the partition, the factor, Ψ, the
residual modes and the projection; the result is a :class:`sarfe.reduction.reduced_model.
ReducedModel`.

Residual vectors (optional, like Nastran's RESVEC): the modes above the cutoff are missing, and
their quasi-static share of the interior response to the boundary's inertia loads is not in Ψ.
With the interior load of unit boundary accelerations, F_i = M_ib + M_ii Ψ (plus any other interior
load columns given, e.g. −M_ii ι_i for base excitation), the static responses

    R₀ = K_ii⁻¹ F_i  (the same factor of K_ii; one block solve with n_b columns)

are M_ii-orthogonalized against Φ and each other, and a Rayleigh–Ritz step in their span
(Rᵀ K_ii R y = ω² Rᵀ M_ii R y) turns them into residual modes Φ_r that keep K_r block diagonal
(Φ_rᵀ K_ii Φ = 0 for exact eigenvectors Φ; the ~1e-7 relative coupling the Lanczos residual leaves
is kept in K_r, which stays the exact Tᵀ K T) and M_r's modal block the identity; their Ritz
frequencies lie above the cutoff. This is the first step of a block Krylov sequence
{Ψ, K_ii⁻¹M Ψ, …}: it lowers the error of a system mode carried mostly by the constraint modes (an
in-plane panel mode, say) from O((ω/ω_i)²) to O((ω/ω_i)⁴), ω_i the lowest omitted interior mode.

Reduced coordinates q = [q_b (n_b, physical, in ``boundary_dofs`` order), q_m (n_m, modal),
q_r (n_r, residual modes)]. Units: K [N/m], M [kg], frequencies [Hz].
"""
from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from sarfe.linalg import factorize
from sarfe.reduction.fixed_interface_modes import column_cap, fixed_interface_modes, start_upper_worker
from sarfe.reduction.lanczos import m_orthonormal
from sarfe.reduction.mode_sinks import park_arrays
from sarfe.reduction.reduced_model import ReducedModel


def residual_modes(stiffness_ii, mass_ii, operator, loads, modes, relative_tolerance=1e-8,
                   static=None):
    """Residual modes Φ_r from interior loads (module docstring): ω_r² (ascending), Φ_r.

    loads: (n_i, k) interior load columns F_i (not read when ``static`` is given); operator(F) =
    K_ii⁻¹ F; modes: Φ (n_i, n_m),
    Φᵀ M_ii Φ = I. Directions whose M-norm after deflation is below relative_tolerance × their norm
    before (already in span Φ, or dependent) are dropped. ``static``: K_ii⁻¹ F_i when already
    computed (then ``operator`` is not called).
    """
    n = mass_ii.shape[0]
    if isinstance(static, list):
        static = static.pop()
    if static is None:
        if loads.shape[1] == 0:
            return np.empty(0), np.empty((n, 0))
        static = operator(np.asarray(loads, dtype=float))
    if static.shape[1] == 0:
        return np.empty(0), np.empty((n, 0))
    mass_static = mass_ii @ static
    norms = np.sqrt(np.einsum("ij,ij->j", static, mass_static))
    static = static[:, norms > 0] / norms[norms > 0]  # unit M-norm before deflation
    mass_static = mass_static[:, norms > 0] / norms[norms > 0]
    for _ in range(2):  # deflate Φ twice (classical Gram–Schmidt, re-orthogonalized)
        static -= modes @ (modes.T @ mass_static)
        mass_static = mass_ii @ static        # (one sparse product per pass; reused below)
    gram = static.T @ mass_static
    values, vectors = np.linalg.eigh(0.5 * (gram + gram.T))
    keep = values > relative_tolerance ** 2   # what is left of a unit column outside span Φ
    if not keep.any():
        return np.empty(0), np.empty((n, 0))
    transform = vectors[:, keep] / np.sqrt(values[keep])
    # (each n_i × k array dropped as soon as its successor exists: no three alive at once)
    block = static @ transform
    del static
    mass_block = mass_static @ transform
    del mass_static
    basis, mass_basis = m_orthonormal(block, mass_ii, mass_block)
    del block, mass_block
    basis -= modes @ (modes.T @ mass_basis)  # the clean-up against Φ
    del mass_basis
    basis, _ = m_orthonormal(basis, mass_ii)
    if basis.shape[1] == 0:
        return np.empty(0), np.empty((n, 0))
    projected = basis.T @ (stiffness_ii @ basis)
    omega2, rotation = np.linalg.eigh(0.5 * (projected + projected.T))
    return omega2, basis @ rotation


def craig_bampton(stiffness, mass, boundary_dofs, mode_count=None, cutoff_hz=None, solver="auto",
                  progress=None, free_dofs=None, total_dof_count=None, eigensolver="block",
                  residual_vectors=False, residual_loads=None, workers=None) -> ReducedModel:
    """Craig–Bampton reduction (see module docstring for the equations).

    stiffness, mass: (n, n) sparse K [N/m], M [kg] on the free DOFs (fixed DOFs removed, see
    :func:`free_dofs_system`); K_ii must be positive definite.
    boundary_dofs: (n_b,) positions in the free-DOF vector kept physically (the caller picks
    components, e.g. translations only via :func:`node_dofs` + :func:`free_dof_positions`).
    mode_count: number of fixed-interface modes; cutoff_hz: keep all modes up to this frequency
    [Hz] (both given: at most mode_count below the cutoff; neither: only static condensation).
    solver: backend for K_ii (see ``linear_solvers``). progress: optional callable(done, total|None)
    called after each mode block. eigensolver: "block" (default: block shift-invert Lanczos with
    12-column multi-RHS solves, :mod:`sarfe.reduction.lanczos`; 35–40 % less CPU than ARPACK on
    the door trim, the same frequencies to ~1e-12; falls back to ARPACK on tiny interiors) or
    "arpack" (:func:`sarfe.reduction.arpack_modes.arpack_modes`). free_dofs/total_dof_count:
    stored for recovery on the original DOF numbering (``free_dofs_system``'s third output).
    residual_vectors: add residual modes for the boundary inertia loads M_ib + M_ii Ψ (module
    docstring); residual_loads: (n, k) further load columns on the free DOFs whose interior part
    gets residual modes too (e.g. the base-excitation load −M ι); either needs one extra block solve.
    workers: processes that slice the spectrum when many modes are wanted (None: the usable
    cores, 1: this process alone; :mod:`sarfe.reduction.spectrum_slicing`); the modes are the same
    for any number.
    """
    stiffness, mass = sp.csr_matrix(stiffness), sp.csr_matrix(mass)
    n = stiffness.shape[0]
    boundary = np.asarray(boundary_dofs, dtype=int)
    if len(np.unique(boundary)) != len(boundary) or boundary.min(initial=0) < 0 or boundary.max(initial=-1) >= n:
        raise ValueError("boundary_dofs must be distinct positions in [0, n)")
    if mode_count is not None and mode_count < 0:
        raise ValueError("mode_count must be >= 0")
    is_interior = np.ones(n, dtype=bool)
    is_interior[boundary] = False
    interior = np.flatnonzero(is_interior)
    timings = {}
    clock = [time.perf_counter(), time.process_time()]

    def lap(stage):
        """Record wall and CPU seconds of the stage that just ended."""
        now = [time.perf_counter(), time.process_time()]
        timings[stage], timings[stage + "_cpu"] = now[0] - clock[0], now[1] - clock[1]
        clock[:] = now

    k_ii = stiffness[interior][:, interior]
    m_ii = mass[interior][:, interior].tocsr()
    k_ib = stiffness[interior][:, boundary].tocsc()     # sparse: n_i × n_b dense is 0.1 GB
    m_ib = mass[interior][:, boundary].tocsc()          # per matrix at 206k DOFs
    k_bb = stiffness[boundary][:, boundary].toarray()
    m_bb = mass[boundary][:, boundary].toarray()
    wants_modes = (mode_count or 0) > 0 or (cutoff_hz is not None and mode_count is None)
    if wants_modes and eigensolver not in ("block", "arpack"):
        raise ValueError(f"eigensolver must be 'block' or 'arpack', got {eigensolver!r}")
    # many modes up to a cutoff: cap run 0's Krylov store (Q, n × cap), slice the rest; the
    # worker is forked now, before K_ii's factor, Ψ and the statics exist (it needs none of
    # them): its PARDISO analysis and count run beside this process's factorization
    cap = column_cap(len(interior), mode_count, cutoff_hz, eigensolver) if wants_modes else None
    upper = start_upper_worker(k_ii, m_ii, cutoff_hz, cap, workers)
    lap("partition")

    try:
        factor = factorize(k_ii, solver=solver, structure="spd")
        lap("factorization")

        psi = -factor.solve(k_ib.toarray()) if len(boundary) else np.empty((len(interior), 0))
        lap("constraint_modes")

        applications = [0]
        held, solver_name = {"factor": factor}, factor.name
        del factor

        def inverse(y):
            applications[0] += 1 if y.ndim == 1 else y.shape[1]
            if held["factor"] is None:        # freed for spectrum slicing, needed again (fallback)
                held["factor"] = factorize(k_ii, solver=solver, structure="spd")
            return held["factor"].solve(y)

        # residual-vector loads and their static responses K_ii⁻¹ F_i, before any mode search (the
        # factor of K_ii may be freed while slicing the spectrum)
        # F_b = M_ib + M_ii Ψ: the interior load of unit boundary accelerations (also M_r's coupling
        # block F_bᵀ Φ); built in place, and shared with the residual-vector loads
        n_b = len(boundary)
        extra = None if residual_loads is None else np.asarray(residual_loads, dtype=float)
        extra = None if extra is None else (extra[:, None] if extra.ndim == 1 else extra)[interior]
        with_boundary = bool(residual_vectors and n_b)
        width = (n_b if with_boundary else 0) + (0 if extra is None else extra.shape[1])
        loads = np.empty((len(interior), width)) if width else None
        boundary_load = loads[:, :n_b] if with_boundary else np.empty((len(interior), n_b))
        boundary_load[:] = m_ii @ psi
        psi_m_psi = psi.T @ boundary_load                               # Ψᵀ M_ii Ψ
        coo = m_ib.tocoo()
        np.add.at(boundary_load, (coo.row, coo.col), coo.data)
        if extra is not None:
            loads[:, width - extra.shape[1]:] = extra
            del extra
        static = inverse(loads) if loads is not None else None
        lap("residual_static")
        restore = None                  # set when the statics wait on disk (two slicing processes)

        if wants_modes:
            if upper is not None:
                # two processes will each hold a Krylov store and a factor: Ψ, the residual loads
                # and their statics (formed after the fork: the worker has no copy) wait on disk
                restore = park_arrays(psi, None if with_boundary else boundary_load, loads, static)
                psi = boundary_load = loads = static = None

            def release_factor():         # run 0 is over: K_ii's factor goes before its modes
                held["factor"] = None     # (inverse() factorizes again if a fallback needs it)

            handed, upper = upper, None   # fixed_interface_modes owns the worker from here
            omega2, blocks, eigensolver = fixed_interface_modes(
                k_ii, m_ii, inverse, mode_count, cutoff_hz, progress, eigensolver, cap, handed,
                release_factor, timings)
            timings["eigensolver"] = eigensolver
        else:
            omega2, blocks = np.empty(0), np.empty((len(interior), 0))
    except BaseException:      # the worker forked above goes too
        if upper is not None:
            upper.cancel()
        raise
    held["factor"] = None
    if restore is not None:
        psi, boundary_load, loads, static = restore()
        boundary_load = loads[:, :n_b] if with_boundary else boundary_load
    lap("normal_modes")

    # T's interior rows [Ψ, Φ, Φ_r] in one array, filled in place (Φ arrives in column blocks
    # when sliced; no stacked copies of an n_i × n_m array)
    blocks = blocks if isinstance(blocks, list) else [blocks]
    n_fixed = len(omega2)
    basis = np.empty((len(interior), n_b + n_fixed + (0 if loads is None else loads.shape[1])))
    basis[:, :n_b] = psi
    psi = basis[:, :n_b]                 # the copy in T serves from here (one n_i × n_b array less)
    column = n_b
    while blocks:
        block = blocks.pop(0)
        basis[:, column:column + block.shape[1]] = block
        column += block.shape[1]
        del block
    phi = basis[:, n_b:n_b + n_fixed]
    if loads is not None:
        # the loads (F_b among them) go before the residual modes' peak: residual_modes frees the
        # statics once used, and F_b = M_ib + M_ii Ψ is formed again below, the same operations
        held_static, static = [static], None
        loads = boundary_load = None
        omega2_r, phi_r = residual_modes(k_ii, m_ii, None, None, phi, static=held_static)
    else:
        omega2_r, phi_r = np.empty(0), np.empty((len(interior), 0))
    basis[:, n_b + n_fixed:n_b + n_fixed + phi_r.shape[1]] = phi_r
    interior_basis = basis[:, :n_b + n_fixed + phi_r.shape[1]]
    lap("residual_modes")
    timings["operator_applications"] = applications[0]
    frequencies = np.sqrt(np.maximum(omega2, 0)) / (2 * np.pi)
    residual_frequencies = np.sqrt(np.maximum(omega2_r, 0)) / (2 * np.pi)
    omega2 = np.concatenate([omega2, omega2_r])
    phi = interior_basis[:, n_b:]
    # dense transients for the n_b × n_b blocks: the same BLAS products (and round-off) as before
    k_rbb = k_bb + k_ib.toarray().T @ psi
    m_ib = m_ib.toarray()
    m_rbb = m_bb + m_ib.T @ psi + psi.T @ m_ib + psi_m_psi
    del m_ib
    if boundary_load is None:
        boundary_load = m_ii @ psi
        np.add.at(boundary_load, (coo.row, coo.col), coo.data)
    m_rbm = boundary_load.T @ phi
    n_b, n_m = len(boundary), len(omega2)
    stiffness_r = np.zeros((n_b + n_m, n_b + n_m))
    mass_r = np.zeros_like(stiffness_r)
    stiffness_r[:n_b, :n_b] = 0.5 * (k_rbb + k_rbb.T)
    stiffness_r[n_b:, n_b:] = np.diag(omega2)
    if len(omega2_r):
        # Φ holds Lanczos eigenvectors to a residual of 1e-8, so Φᵀ K_ii Φ_r is ~1e-7 of the
        # diagonal rather than 0: keep the exact Galerkin coupling
        n_fixed = n_m - len(omega2_r)
        coupling = phi[:, :n_fixed].T @ (k_ii @ phi_r)
        stiffness_r[n_b:n_b + n_fixed, n_b + n_fixed:] = coupling
        stiffness_r[n_b + n_fixed:, n_b:n_b + n_fixed] = coupling.T
    mass_r[:n_b, :n_b] = 0.5 * (m_rbb + m_rbb.T)
    mass_r[:n_b, n_b:] = m_rbm
    mass_r[n_b:, :n_b] = m_rbm.T
    mass_r[n_b:, n_b:] = np.eye(n_m)
    lap("projection")

    return ReducedModel(
        mass=mass_r, stiffness=stiffness_r, boundary_dofs=boundary, interior_dofs=interior,
        interior_basis=interior_basis, mode_frequencies_hz=frequencies,
        residual_frequencies_hz=residual_frequencies,
        full_dof_count=n, free_dofs=None if free_dofs is None else np.asarray(free_dofs, dtype=int),
        total_dof_count=total_dof_count, solver=solver_name, timings=timings)
