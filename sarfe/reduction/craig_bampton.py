r"""Craig–Bampton reduction of (K, M) to boundary DOFs + fixed-interface modes.

Partition the free DOFs into boundary b (kept physically: contact, excitation, response points)
and interior i. With u_b = q_b and

    u_i = Ψ q_b + Φ q_m,     Ψ = −K_ii⁻¹ K_ib  (constraint modes, static condensation),
                             K_ii Φ = M_ii Φ Ω²,  Φᵀ M_ii Φ = I  (fixed-interface normal modes),

the transformation u = T q, T = [[I, 0], [Ψ, Φ]], gives K_r = Tᵀ K T and M_r = Tᵀ M T:

    K_r = [[K_bb + K_bi Ψ, 0], [0, Ω²]]
    M_r = [[M_bb + M_bi Ψ + Ψᵀ M_ib + Ψᵀ M_ii Ψ, (M_bi + Ψᵀ M_ii) Φ], [sym, I]]

K_ii is factorized once (``sarfe.linalg.factorize``) and that factor serves Ψ
(one block solve with n_b right-hand sides) and the shift-invert Lanczos iteration for Φ: by
default a block Lanczos on K_ii⁻¹ M_ii whose steps are multi-RHS solves (one σ = 0 engine,
:func:`sarfe.reduction.lanczos.shifted_block_lanczos`: uncapped in :func:`_block_lanczos_modes`,
capped as run 0 of spectrum slicing in :func:`_capped_run0`); alternatively ARPACK
(:func:`sarfe.reduction.arpack_modes.arpack_modes`: ``eigsh`` with σ = 0, deflated blocks for a
cutoff). This module holds the partition, the factor, Ψ, the mode search dispatch, the residual
modes and the projection.

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
import weakref
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from sarfe.linalg import available_solvers, factorize
from sarfe.reduction.arpack_modes import arpack_modes
from sarfe.reduction.lanczos import m_orthonormal, shifted_block_lanczos
from sarfe.reduction.mode_sinks import FileSink
from sarfe.reduction.spectrum_slicing import SlicingFailed, sliced_modes, start_upper_slices

# a σ = 0 block Lanczos run keeps at most max(_SLICE_COLUMNS, _SLICE_ENTRIES / n) Krylov columns;
# past that the modes up to the cutoff come from spectrum slicing (Q: 0.79 GB at n = 206k). Run 0
# finds its modes at half the CPU per mode of a shifted run (door trim at 5 mm: 0.08 against
# 0.15 s), so its cap is above the shifted runs' 400 columns: 480 columns found 191 modes in
# 15 s CPU (400: 141 in 11 s), and the two processes then finish within 0.5 s of each other
_SLICE_COLUMNS = 480
_SLICE_ENTRIES = 8e7
# a second process slices the upper part of the spectrum when the modes below the cutoff
# outnumber what run 0 finds in its capped space (≈ 0.35 modes per column on the door trim). The
# split is by count: this process (run 0 and the shifted runs up to λ_s) takes N(λ_s) ≈ (N(λ_c) +
# lead)/2 modes, lead = _RUN0_LEAD_PER_COLUMN · run 0's column cap — run 0 finds its modes (191 at
# a cap of 480 on the door trim at 5 mm) for the CPU time of ≈ 100 shifted-run modes (15 s against
# 0.15 s per mode): lead ≈ 0.2 per column. The runs are whole (≈ 9 s each), so the two processes
# finish within a run's fraction: at a cap of 400, lead 0.12 gave the door trim's worker a
# fourth, tiny run (this process waited 3 s for it) and 0.2 left the worker 3 s idle
# (benchmarks/results/linear.md)
_PARALLEL_MODES_PER_COLUMN = 0.5
_RUN0_LEAD_PER_COLUMN = 0.2
# run 0 may go on past its cap by this fraction of it when the modes still missing below the
# split are that few (at its own rate so far): a shifted run spends ≈ 150 columns (0.3 of the cap)
# before its window converges, plus a factorization; P1 at 1.0 H f_max (339 modes): 27 modes
# were missing at the cap of 480, ≈ 70 more columns for run 0 instead of a 264-column shifted run
_RUN0_EXTENSION = 0.25


@dataclass(frozen=True, eq=False)  # array fields: compare explicitly, not with ==
class ReducedModel:
    """Craig–Bampton model on q = [q_b, q_m] (n_r = n_b + n_m).

    mass, stiffness: (n_r, n_r) dense [kg], [N/m]; damping: (n_r, n_r) [N s/m] or None.
    boundary_dofs: (n_b,) positions of the boundary DOFs in the free-DOF vector (length
    ``full_dof_count``); interior_dofs: (n_i,) the others, in increasing order.
    interior_basis: (n_i, n_r) = [Ψ, Φ], the interior rows of T (u_i = interior_basis @ q).
    mode_frequencies_hz: (n_m,) fixed-interface natural frequencies; residual_frequencies_hz:
    (n_rv,) Ritz frequencies of the residual modes (after the fixed-interface modes in q).
    free_dofs: (full_dof_count,) original (unconstrained) DOF number of each free DOF, or None if the
    free-DOF vector is the original one; total_dof_count: length of the original DOF vector.
    timings: wall seconds per stage (partition, factorization, constraint_modes, normal_modes,
    projection), the same with suffix "_cpu" in CPU seconds, and operator_applications (K_ii⁻¹ columns).
    """

    mass: np.ndarray
    stiffness: np.ndarray
    boundary_dofs: np.ndarray
    interior_dofs: np.ndarray
    interior_basis: np.ndarray
    mode_frequencies_hz: np.ndarray
    full_dof_count: int
    damping: np.ndarray | None = None
    free_dofs: np.ndarray | None = None
    total_dof_count: int | None = None
    solver: str = ""
    timings: dict = field(default_factory=dict, compare=False)
    residual_frequencies_hz: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def boundary_count(self) -> int:
        return len(self.boundary_dofs)

    @property
    def mode_count(self) -> int:
        return len(self.mode_frequencies_hz)

    @property
    def residual_vector_count(self) -> int:
        return len(self.residual_frequencies_hz)

    @property
    def reduced_dof_count(self) -> int:
        return self.boundary_count + self.mode_count + self.residual_vector_count

    @property
    def constraint_modes(self) -> np.ndarray:
        """Ψ (n_i, n_b): interior response to unit boundary displacements."""
        return self.interior_basis[:, : self.boundary_count]

    @property
    def fixed_interface_modes(self) -> np.ndarray:
        """Φ (n_i, n_m), mass-normalized on M_ii."""
        return self.interior_basis[:, self.boundary_count:self.boundary_count + self.mode_count]

    @property
    def residual_modes(self) -> np.ndarray:
        """Φ_r (n_i, n_rv): residual modes (module docstring), mass-normalized, M- and K-orthogonal to Φ."""
        return self.interior_basis[:, self.boundary_count + self.mode_count:]

    @property
    def size_reduction(self) -> dict:
        """Free DOFs, reduced DOFs, boundary DOFs, modes and the ratio free/reduced."""
        return {"free_dofs": self.full_dof_count, "reduced_dofs": self.reduced_dof_count,
                "boundary_dofs": self.boundary_count, "modes": self.mode_count,
                "residual_vectors": self.residual_vector_count,
                "ratio": self.full_dof_count / max(self.reduced_dof_count, 1)}


def free_dofs_system(stiffness, mass, fixed_dofs):
    """Remove fixed (clamped) DOFs: K_ff, M_ff (CSR) and free_dofs (n_f,) original DOF numbers.

    fixed_dofs: original DOF numbers held at zero (duplicates allowed).
    """
    n = stiffness.shape[0]
    keep = np.ones(n, dtype=bool)
    keep[np.asarray(fixed_dofs, dtype=int)] = False
    free = np.flatnonzero(keep)
    stiffness, mass = sp.csr_matrix(stiffness), sp.csr_matrix(mass)
    return stiffness[free][:, free].tocsr(), mass[free][:, free].tocsr(), free


def free_dof_positions(dofs, free_dofs, total_dof_count=None):
    """Positions in the free-DOF vector of original DOF numbers ``dofs``. Raises if one is fixed."""
    dofs = np.asarray(dofs, dtype=int)
    if free_dofs is None:
        return dofs
    total = int(total_dof_count if total_dof_count is not None else free_dofs.max() + 1)
    position = np.full(max(total, dofs.max(initial=-1) + 1), -1, dtype=int)
    position[free_dofs] = np.arange(len(free_dofs))
    out = position[dofs]
    if np.any(out < 0):
        raise ValueError(f"DOFs {dofs[out < 0][:5].tolist()} are fixed, not free")
    return out


def node_dofs(nodes, components=(0, 1, 2), dofs_per_node: int = 6) -> np.ndarray:
    """Original DOF numbers dofs_per_node*node + component, node-major, e.g. translations only."""
    nodes = np.asarray(nodes, dtype=int)
    return (dofs_per_node * nodes[:, None] + np.asarray(components, dtype=int)[None, :]).ravel()


@dataclass(frozen=True, eq=False)
class _Partial:
    """A σ = 0 Lanczos run stopped at its column cap: its converged eigenpairs, all ω² ≤ boundary
    (``stats``: its steps, full re-orthogonalization passes and sparse products M·(n, b))."""

    omega2: np.ndarray
    modes: np.ndarray
    boundary: float
    columns: int
    stats: dict = field(default_factory=dict)


def _capped_run0(mass_ii, operator, cutoff_hz, progress, max_columns, release_operator=None,
                 keep_prefix=None, block_size=12, tol=1e-8, seed=0, split_plan=None):
    """Run 0 of spectrum slicing: block Lanczos on K_ii⁻¹ M_ii (σ = 0) from a block of
    ``block_size`` columns, stopped at ``max_columns`` columns, with the shifted runs' partial
    re-orthogonalization (:func:`sarfe.reduction.lanczos.shifted_block_lanczos` at
    σ = 0: a full M-re-orthogonalization pass only when Simon's estimate of the lost
    orthogonality exceeds 1e-10, one sparse product M·(n, b) per step without it). A Ritz pair
    is converged when ‖A φ − θ φ‖_M ≤ tol·θ, θ = 1/ω², relative to its own θ.

    Returns (ω² (k,) ascending, Φ (n, k), Φᵀ M Φ = I) when every mode up to the cutoff has
    converged within the cap; else the converged prefix as :class:`_Partial` (its boundary
    halfway to the next Ritz value; ``keep_prefix(modes)``, when given, returns what it holds
    instead of the vectors: the sink's handle); None when nothing converged. ``release_operator()``
    is called after the last operator application, before the Ritz vectors are formed.

    ``split_plan()`` (two processes): the other process's split (λ_s, N(λ_s)), or None. At the
    cap, when the modes still missing below λ_s would take run 0 at most _RUN0_EXTENSION · cap
    more columns at its own rate so far (converged prefix / columns), run 0 goes on until its
    converged prefix holds N(λ_s) values ≤ λ_s and one above: those few modes then cost run 0
    tens of columns instead of a shifted run of ≈ 150 columns before its window converges plus
    a factorization (the caller certifies the prefix by the count N(λ_s)).
    """
    cutoff_omega2 = (2 * np.pi * cutoff_hz) ** 2
    extension = {"split": None, "decided": split_plan is None}

    def converged_prefix(lam, converged):
        order = np.argsort(lam)
        flags = converged[order]
        prefix = int(np.argmin(flags)) if not flags.all() else len(flags)
        return order, prefix, int(np.count_nonzero(lam <= cutoff_omega2))

    def satisfied(lam, converged):
        order, prefix, wanted = converged_prefix(lam, converged)
        if progress is not None:
            progress(min(prefix, wanted), None)
        if prefix > wanted:                 # every mode up to the cutoff, and one above it
            return True
        if len(lam) < max_columns:
            return False
        split = extension["split"]
        if not extension["decided"]:        # at the cap: go on toward the split?
            extension["decided"] = True
            split = split_plan()
            if split is not None:
                missing = split[1] - np.count_nonzero(lam[order[:prefix]] <= split[0])
                if missing > _RUN0_EXTENSION * max_columns * prefix / len(lam):
                    split = None
            extension["split"] = split
        if split is None:
            return True
        below = np.count_nonzero(lam[order[:prefix]] <= split[0])
        return below >= split[1] and prefix > below

    stats = {}
    limit = max_columns if split_plan is None else int((1 + _RUN0_EXTENSION) * max_columns)
    lam, converged, eigenvectors = shifted_block_lanczos(mass_ii, operator, 0.0, satisfied,
                                                         limit, block_size, tol, seed, stats)
    if extension["split"] is not None:
        stats["extended_to_split"] = int(extension["split"][1])
    if release_operator is not None:
        release_operator()
    order, prefix, wanted = converged_prefix(lam, converged)
    if prefix > wanted:
        return lam[order[:wanted]], eigenvectors(order[:wanted])
    if prefix == 0:
        return None
    modes = eigenvectors(order[:prefix])
    boundary = 0.5 * (lam[order[prefix - 1]] + lam[order[prefix]]) if prefix < len(lam) \
        else float(lam[order[-1]])
    return _Partial(lam[order[:prefix]], modes if keep_prefix is None else keep_prefix(modes),
                    boundary, len(lam), stats)


def _block_lanczos_modes(mass_ii, operator, mode_count, cutoff_hz, progress, block_size=12,
                         tol=1e-8, seed=0, stats=None):
    """Lowest modes of K_ii φ = ω² M_ii φ by one uncapped σ = 0 block Lanczos run on
    A = K_ii⁻¹ M_ii (:func:`sarfe.reduction.lanczos.shifted_block_lanczos` at σ = 0: ω² = 1/θ,
    partial M-re-orthogonalization, a Ritz pair converged when ‖A φ − θ φ‖_M ≤ tol·θ).

    mass_ii: (n_i, n_i) sparse M_ii [kg]; operator(Y) = K_ii⁻¹ Y (n_i, b); mode_count: modes wanted
    and/or cutoff_hz [Hz]: every mode up to it. The run stops when its converged prefix (the
    lowest Ritz values, in order, all converged) holds every mode wanted: mode_count of them, or
    every mode ≤ cutoff plus one above it (so none below is missing; with both, the first
    min(mode_count, N(cutoff)) and one more). Eigenvalue error ~ residual², so tol = 1e-8 gives
    frequencies to ~1e-15. Returns ω² (ascending, [rad²/s²]) and Φ (n_i, n_m), Φᵀ M_ii Φ = I, or
    None when the Krylov space fills the interior first (tiny models: the caller uses ARPACK).
    The Krylov store starts at ≈ 5 columns per mode wanted (64 modes' worth for a cutoff alone)
    and doubles when full, never n_i columns up front. (A cutoff with many modes caps the σ = 0
    run instead: :func:`_capped_run0`, then spectrum slicing.)
    """
    n = mass_ii.shape[0]
    cutoff_omega2 = (2 * np.pi * cutoff_hz) ** 2 if cutoff_hz is not None else np.inf
    target = mode_count if mode_count is not None else n
    guess = min(target, n) if mode_count is not None else 64
    capacity = 5 * guess + 2 * block_size          # measured: ~4.8 columns per mode

    def prefix_and_wanted(lam, converged):
        """Ascending order of λ (θ ≤ 0, none at σ = 0 but for round-off, last), the converged
        prefix's length and the number of modes wanted among those found."""
        order = np.argsort(np.where(lam > 0, lam, np.inf))
        flags = converged[order]
        prefix = int(np.argmin(flags)) if not flags.all() else len(flags)
        wanted = min(target, len(lam))
        if cutoff_hz is not None:
            wanted = min(wanted, int(np.count_nonzero((lam > 0) & (lam <= cutoff_omega2))))
        done = prefix > wanted if cutoff_hz is not None else prefix >= target
        return order, prefix, wanted, done

    def satisfied(lam, converged):
        _, prefix, _, done = prefix_and_wanted(lam, converged)
        if progress is not None:
            progress(min(prefix, target), mode_count)
        return done

    lam, converged, eigenvectors = shifted_block_lanczos(mass_ii, operator, 0.0, satisfied, n,
                                                         block_size, tol, seed, stats,
                                                         capacity=capacity)
    order, _, wanted, done = prefix_and_wanted(lam, converged)
    if not done:
        return None  # Krylov space exhausted before convergence (tiny interior): caller uses ARPACK
    return lam[order[:wanted]], eigenvectors(order[:wanted])


def _two_processes(workers):
    """Whether spectrum slicing may run in two processes: ``workers`` ≥ 2 (None: the usable
    cores) and PARDISO (the worker's inertia counts)."""
    from sarfe.util.workers import available_cpus

    workers = available_cpus() if workers is None else int(workers)
    return workers >= 2 and "pardiso" in available_solvers()


def _start_upper_slices(k_ii, m_ii, cutoff_hz, cap):
    """Right after the partition (before K_ii is factorized), a forked worker that counts the
    modes below the cutoff and, when they outnumber what run 0 finds in its capped space, slices
    the upper part of the spectrum while this process factorizes K_ii, forms Ψ and the residual
    statics, runs run 0 and the lower part
    (:func:`sarfe.reduction.spectrum_slicing.start_upper_slices`). None where it cannot start."""
    try:
        return start_upper_slices(k_ii, m_ii, (2 * np.pi * cutoff_hz) ** 2,
                                  _RUN0_LEAD_PER_COLUMN * cap,
                                  int(_PARALLEL_MODES_PER_COLUMN * cap))
    except OSError:               # no temporary file or no process: one process does it all
        return None


def _park(*arrays):
    """Write (n, k) arrays (or None) to a temporary file on disk and return a function that reads
    them back, in their memory order, and removes the file (:mod:`sarfe.reduction.mode_sinks`)."""
    sink = FileSink(next(a.shape[0] for a in arrays if a is not None))
    try:
        parked = [None if a is None else (sink.put(a), "F" if np.isfortran(a) else "C")
                  for a in arrays]
    except BaseException:
        sink.remove()
        raise

    def restore():
        try:
            return [None if p is None else np.array(sink.read(p[0]), order=p[1])
                    for p in parked]
        finally:
            sink.remove()

    weakref.finalize(restore, sink.remove)      # an error on the way: the file goes too
    return restore


def _file_sink(rows):
    """A :class:`sarfe.reduction.mode_sinks.FileSink` for this process's found vectors."""
    return FileSink(rows)


def _worker_splits(upper):
    """Wait for the worker's count below the cutoff: True when it slices the upper part (else it
    has exited); its split comes later (:meth:`UpperSlices.plan`, after run 0)."""
    try:
        return upper.splits()
    except SlicingFailed:
        return False


def _split_plan(upper):
    """A function returning the worker's split (λ_s, N(λ_s)), or None when it failed placing it
    (the caller then finds the failure again in :meth:`UpperSlices.plan`)."""
    def split_plan():
        try:
            return upper.plan()[1:]
        except SlicingFailed:
            return None

    return split_plan


def _slice(k_ii, m_ii, cutoff_hz, partial, progress, timings, upper, sink):
    """Modes up to the cutoff by spectrum slicing from run 0's converged prefix (with the upper
    part from ``upper``'s worker when given; ``sink``: where the found vectors wait, None: in
    memory): (ω², Φ as column blocks), or None when slicing cannot run (no PARDISO for the
    inertia) or a gap's count was not reached."""
    if "pardiso" not in available_solvers():
        if sink is not None:
            sink.remove()
        return None
    try:
        omega2, modes, record = sliced_modes(k_ii, m_ii, (2 * np.pi * cutoff_hz) ** 2,
                                             partial.omega2, partial.modes, partial.boundary,
                                             progress=progress, solver="pardiso", upper=upper,
                                             sink=sink)
    except SlicingFailed as exc:
        timings["slicing"] = {"failed": str(exc)}
        return None
    timings["slicing"] = dict(record, run0_columns=partial.columns, run0_modes=len(partial.omega2),
                              **{"run0_" + key: value for key, value in partial.stats.items()})
    return omega2, modes


def residual_modes(stiffness_ii, mass_ii, operator, loads, modes, relative_tolerance=1e-8,
                   static=None):
    """Residual modes Φ_r from interior loads (module docstring): ω_r² (ascending), Φ_r.

    loads: (n_i, k) interior load columns F_i; operator(F) = K_ii⁻¹ F; modes: Φ (n_i, n_m),
    Φᵀ M_ii Φ = I. Directions whose M-norm after deflation is below relative_tolerance × their norm
    before (already in span Φ, or dependent) are dropped. ``static``: K_ii⁻¹ F_i when already
    computed (then ``operator`` is not called).
    """
    n = mass_ii.shape[0]
    if loads.shape[1] == 0:
        return np.empty(0), np.empty((n, 0))
    if static is None:
        static = operator(np.asarray(loads, dtype=float))
    mass_static = mass_ii @ static
    norms = np.sqrt(np.einsum("ij,ij->j", static, mass_static))
    static = static[:, norms > 0] / norms[norms > 0]  # unit M-norm before deflation
    mass_static = mass_static[:, norms > 0] / norms[norms > 0]
    for _ in range(2):  # deflate Φ twice (classical Gram–Schmidt, re-orthogonalized)
        static = static - modes @ (modes.T @ mass_static)
        mass_static = mass_ii @ static        # (one sparse product per pass; reused below)
    gram = static.T @ mass_static
    values, vectors = np.linalg.eigh(0.5 * (gram + gram.T))
    keep = values > relative_tolerance ** 2   # what is left of a unit column outside span Φ
    if not keep.any():
        return np.empty(0), np.empty((n, 0))
    transform = vectors[:, keep] / np.sqrt(values[keep])
    basis, mass_basis = m_orthonormal(static @ transform, mass_ii, mass_static @ transform)
    basis = basis - modes @ (modes.T @ mass_basis)  # the clean-up against Φ
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
    # many modes up to a cutoff: cap run 0's Krylov store (Q, n × cap), slice the rest
    cap = max(_SLICE_COLUMNS, int(_SLICE_ENTRIES // max(len(interior), 1))) \
        if wants_modes and eigensolver == "block" and cutoff_hz is not None \
        and mode_count is None else None
    cap = cap if cap is not None and cap < len(interior) else None     # a cap ≥ n: no cap
    two = cap is not None and _two_processes(workers)
    # the worker is forked now, before K_ii's factor, Ψ and the statics exist (it needs none of
    # them): its PARDISO analysis and count run beside this process's factorization
    upper = _start_upper_slices(k_ii, m_ii, cutoff_hz, cap) if two else None
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
            found = None
            if eigensolver == "block":
                if upper is not None:
                    # two processes will each hold a Krylov store and a factor: Ψ, the residual loads
                    # and their statics (formed after the fork: the worker has no copy) wait on disk
                    restore = _park(psi, None if with_boundary else boundary_load, loads, static)
                    psi = boundary_load = loads = static = None
                if upper is not None and not _worker_splits(upper):
                    upper = None              # few modes: run 0 as in one process
                # two processes: the found vectors wait on disk while both slice (mode_sinks)
                sink = _file_sink(len(interior)) if upper is not None else None

                def release_factor():         # run 0 is over: K_ii's factor goes before its modes
                    held["factor"] = None     # (inverse() factorizes again if a fallback needs it)

                if cap is None:
                    found = _block_lanczos_modes(m_ii, inverse, mode_count, cutoff_hz, progress)
                else:
                    found = _capped_run0(m_ii, inverse, cutoff_hz, progress, cap, release_factor,
                                         None if sink is None else sink.put,
                                         split_plan=None if upper is None else
                                         _split_plan(upper))
                if isinstance(found, _Partial):
                    held["factor"] = None     # K_ii's factor is not used by the shifted runs
                    found = _slice(k_ii, m_ii, cutoff_hz, found, progress, timings, upper, sink)
                elif upper is not None:
                    upper.cancel()            # run 0 found them all after all
                    sink.remove()
                upper = sink = None
                if found is None and cap is not None:   # slicing impossible: one uncapped run
                    found = _block_lanczos_modes(m_ii, inverse, mode_count, cutoff_hz, progress)
            if found is None:
                found = arpack_modes(k_ii, m_ii, inverse, mode_count, cutoff_hz, progress)
                eigensolver = "arpack"
            omega2, blocks = found
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
    column = n_b
    while blocks:
        block = blocks.pop(0)
        basis[:, column:column + block.shape[1]] = block
        column += block.shape[1]
        del block
    phi = basis[:, n_b:n_b + n_fixed]
    if loads is not None:
        omega2_r, phi_r = residual_modes(k_ii, m_ii, None, loads, phi, static=static)
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
