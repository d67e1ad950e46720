r"""The fixed-interface normal modes of Craig–Bampton: K_ii φ = ω² M_ii φ, Φᵀ M_ii Φ = I.

:func:`fixed_interface_modes` is the mode search behind
:func:`sarfe.reduction.craig_bampton.craig_bampton`, on the factor of K_ii the constraint modes
Ψ = −K_ii⁻¹ K_ib used (``inverse(Y) = K_ii⁻¹ Y``):

- a mode count, or a cutoff with few modes: one uncapped block Lanczos run on A = K_ii⁻¹ M_ii
  (σ = 0, :func:`sarfe.reduction.lanczos.shifted_block_lanczos`; ω² = 1/θ);
- a cutoff with many modes: the same run capped at :func:`column_cap` columns ("run 0"), then
  spectrum slicing (:mod:`sarfe.reduction.spectrum_slicing`: shifted runs whose counts Sylvester's
  inertia certifies), the upper part of the spectrum in a second, forked process when
  :func:`start_upper_worker` started one (the found vectors then wait on disk,
  :mod:`sarfe.reduction.mode_sinks`);
- ARPACK (:func:`sarfe.reduction.arpack_modes.arpack_modes`) when asked, or when the Krylov space
  of a tiny interior fills before convergence.

Units: M_ii [kg], K_ii [N/m], ω² [rad²/s²], cutoff [Hz].
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from sarfe.linalg import available_solvers
from sarfe.reduction.arpack_modes import arpack_modes
from sarfe.reduction.lanczos import shifted_block_lanczos
from sarfe.reduction.mode_sinks import FileSink
from sarfe.reduction.spectrum_slicing import SlicingFailed, sliced_modes, start_upper_slices
from sarfe.util import workers as process_pool

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


def column_cap(interior_count, mode_count, cutoff_hz, eigensolver):
    """Run 0's Krylov column cap when many modes up to a cutoff are wanted from the block
    Lanczos (max(_SLICE_COLUMNS, _SLICE_ENTRIES / n_i): the store Q is n_i × cap), else None
    (no cap: a mode count, ARPACK, or a cap ≥ n_i)."""
    cap = max(_SLICE_COLUMNS, int(_SLICE_ENTRIES // max(interior_count, 1))) \
        if eigensolver == "block" and cutoff_hz is not None and mode_count is None else None
    return cap if cap is not None and cap < interior_count else None


def start_upper_worker(k_ii, m_ii, cutoff_hz, cap, workers):
    """The forked worker that slices the upper part of the spectrum (:func:`_start_upper_slices`)
    when run 0 is capped (``cap`` not None) and two processes may slice (:func:`_two_processes`),
    else None. Start it right after the partition, before K_ii is factorized."""
    if cap is None or not _two_processes(workers):
        return None
    return _start_upper_slices(k_ii, m_ii, cutoff_hz, cap)


def _two_processes(workers):
    """Whether spectrum slicing may run in two processes: ``workers`` ≥ 2 (None: the usable
    cores) and PARDISO (the worker's inertia counts)."""
    workers = process_pool.available_cpus() if workers is None else int(workers)
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


def fixed_interface_modes(k_ii, m_ii, inverse, mode_count, cutoff_hz, progress, eigensolver,
                          cap=None, upper=None, release_factor=None, timings=None):
    """Fixed-interface modes (module docstring): (ω² (n_m,) ascending [rad²/s²], Φ (n_i, n_m) or
    a list of its column blocks, the eigensolver that found them: "block" or "arpack").

    k_ii, m_ii: sparse K_ii [N/m], M_ii [kg]; inverse(Y) = K_ii⁻¹ Y (n_i, b); mode_count and/or
    cutoff_hz [Hz] as in :func:`sarfe.reduction.craig_bampton.craig_bampton`; progress: optional
    callable(done, total|None); eigensolver: "block" or "arpack"; cap: :func:`column_cap`;
    upper: the worker of :func:`start_upper_worker` or None (this function owns it: it is joined,
    or cancelled on any error); release_factor(): called when K_ii's factor is no longer needed
    (run 0 is over; ``inverse`` must factorize again if a fallback needs it); timings: dict that
    receives the slicing record under "slicing".
    """
    timings = {} if timings is None else timings
    release_factor = release_factor if release_factor is not None else (lambda: None)
    try:
        found = None
        if eigensolver == "block":
            if upper is not None and not _worker_splits(upper):
                upper = None              # few modes: run 0 as in one process
            # two processes: the found vectors wait on disk while both slice (mode_sinks)
            sink = FileSink(m_ii.shape[0]) if upper is not None else None
            if cap is None:
                found = _block_lanczos_modes(m_ii, inverse, mode_count, cutoff_hz, progress)
            else:
                found = _capped_run0(m_ii, inverse, cutoff_hz, progress, cap, release_factor,
                                     None if sink is None else sink.put,
                                     split_plan=None if upper is None else _split_plan(upper))
            if isinstance(found, _Partial):
                release_factor()          # K_ii's factor is not used by the shifted runs
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
    except BaseException:
        if upper is not None:
            upper.cancel()
        raise
    omega2, blocks = found
    return omega2, blocks, eigensolver
