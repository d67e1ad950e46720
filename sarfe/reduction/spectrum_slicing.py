r"""Many fixed-interface modes at bounded memory: shift-invert block Lanczos in slices of the
spectrum, each slice certified complete by Sylvester's inertia.

One Lanczos run from σ = 0 finds the lowest modes cheaply, but for hundreds of modes its Krylov
space grows to ~5 columns per mode (the wanted ν = 1/ω² crowd towards 0 next to the unwanted
ones) and full re-orthogonalization costs n·m² (m columns): the door trim at 5 mm, 471 modes up to
1.5 kHz, took 200 s and 6.5 GB that way. Here the spectrum (0, λ_c] (λ = ω², λ_c the cutoff) is
cut at shifts 0 = σ_0 < σ_1 < … < σ_s = λ_c. Run j factorizes K − σ_j M (symmetric indefinite,
LDLᵀ) and iterates on

    A_j = (K − σ_j M)⁻¹ M,   A_j φ = θ φ,   λ = σ_j + 1/θ,

whose largest |θ| — the eigenvalues nearest σ_j, on both sides — converge first. The factor's
negative pivots count the eigenvalues below σ_j (Sylvester), so each gap (σ_{j−1}, σ_j] has a known
count c_j = n_j − n_{j−1}; it is filled by run j−1's converged values above σ_{j−1} (up to a
boundary r_{j−1} placed in a spectral gap) and run j's converged values in (r_{j−1}, σ_j], and run
j iterates until the two add up to c_j (or run j alone finds all c_j). Shifts are placed from the
eigenvalue count so far, N(λ) ≈ a √λ (a plate's modal density), so that a run's window holds
about ``slice_modes`` eigenvalues; each run's Krylov space is bounded by ``max_columns``.

Run 0 is the caller's σ = 0 block Lanczos stopped at its column cap; its converged prefix and the
next Ritz value enter here as (eigenvalues, modes, boundary).

Every shift's K − σM has the same sparsity pattern: PARDISO's ordering and symbolic analysis run
once (:func:`sarfe.linalg.shifted_factorizer`), each shift only its numerical LDLᵀ.

Two processes (two usable cores): a chain of runs needs nothing from another chain but a
certified count at its bottom, so the spectrum is split at a shift λ_s chosen by count. A worker
forked right after Craig–Bampton's partition (while this process factorizes K_ii and forms Ψ and
the residual statics) counts N(λ_c) and tells this process whether it splits; it then places λ_s so
that N(λ_s) ≈ (N(λ_c) + lead)/2 (:func:`split_count`: this process's run 0 finds its modes at a
lower cost per mode than the shifted runs, ``lead`` modes ahead) from one or two factorizations
whose inertia gives exact counts (:func:`split_shift`), and runs the chain over (λ_s, λ_c] from
nothing pending; this process runs run 0 and the chain over (boundary, λ_s], then appends the
worker's block. The split and both chains' shifts follow from the model and the counts alone, so
the modes do not depend on timing; with one core, no fork, or inside a daemon process (a Dask
worker) one chain covers it all.

Memory with two processes: each holds a Krylov store (up to ``max_columns`` = 400 columns, 0.66
GB at 206k DOFs) and a factor of K − σM (0.32 GB) at once, so the vectors both have found wait
on disk until Craig–Bampton copies them (:class:`~sarfe.reduction.mode_sinks.FileSink`, run 0's
prefix included), and run 0's factor of K_ii goes before its Ritz vectors are formed. A smaller
column cap would save memory too but costs CPU steeply: each run spends ≈ 150 columns before its
window converges (door trim at 5 mm, cap 240 with windows of 48: 262 s CPU instead of 100 s;
benchmarks/results/linear.md, P1 memory).

Every run (run 0 at σ = 0 too) is :func:`sarfe.reduction.lanczos.shifted_block_lanczos`: the M
inner product, a Ritz pair converged when ‖A φ − θ φ‖_M ≤ tol·|θ| (relative to its own θ: a value
next to the shift, with a huge θ, must not loosen the test for the others), partial
re-orthogonalization, blocks of 12 columns (that module's docstring has the measurements).
"""
from __future__ import annotations

import os
import time
from dataclasses import dataclass

import numpy as np

from sarfe.linalg import shifted_factorizer
from sarfe.reduction.mode_sinks import FileSink, MemorySink
from sarfe.reduction.lanczos import shifted_block_lanczos


class SlicingFailed(RuntimeError):
    """A gap's eigenvalue count was not reached within the column cap (the caller falls back)."""


def _place_shift(factor_at, right_edge, known, wanted, top_omega2, total, rate, record):
    """The next shift σ > right_edge with about ``wanted`` eigenvalues in (right_edge, σ] and its
    factor of K − σM (``factor_at(σ)``); the interval's top itself once at most 1.25 ``wanted``
    remain below it (``total`` eigenvalues ≤ top, ``known`` ≤ right_edge). First guess
    ω = √right_edge + wanted / rate (``rate``: eigenvalues per rad/s the last run saw; None: N(ω)
    linear up to the top); a factor whose inertia shows more than 1.5× or fewer than 0.5×
    ``wanted`` is replaced (three times at most) by the interpolation through that probe."""
    omega, top = np.sqrt(right_edge), np.sqrt(top_omega2)
    if total - known <= 1.25 * wanted:
        factor = factor_at(top_omega2)
        record["factorizations"] += 1
        return top_omega2, factor
    guess = omega + wanted / rate if rate else omega + (top - omega) * wanted / (total - known)
    for attempt in range(4):
        shift = min(guess, top) ** 2
        factor = factor_at(shift)
        record["factorizations"] += 1
        inside = factor.negative_pivots - known
        if 0.5 * wanted <= inside <= 1.5 * wanted or attempt == 3 or (shift >= top_omega2
                                                                      and inside <= 1.5 * wanted):
            return shift, factor
        del factor
        guess = omega + (np.sqrt(shift) - omega) * wanted / max(inside, 1)
    return shift, factor


def _slice_run(mass, factor, shift, lower, counted, right_edge, pending, max_columns, last,
               stats=None):
    """One shifted Lanczos run for the gap (lower, shift] (module docstring). Returns (λ,
    converged, eigenvectors, take: the run's values kept for the gap, use_pending: whether the
    previous run's values ≤ shift complete it) or raises SlicingFailed."""
    gap_count = factor.negative_pivots - counted           # eigenvalues in (lower, shift]
    need_left = gap_count - sum(1 for v in pending if v <= shift)
    half_width = shift - right_edge
    state = {}

    def satisfied(lam, converged):
        left = converged & (lam > right_edge) & (lam <= shift)
        alone = converged & (lam > lower) & (lam <= shift)
        state["alone"] = np.count_nonzero(alone) == gap_count
        state["left"] = np.count_nonzero(left) == need_left
        if not (state["left"] or state["alone"]):
            return False
        if last:
            return True
        # the right side: every Ritz value within the mirrored window has converged
        open_right = (lam > shift) & ~converged & (lam <= shift + half_width)
        return not open_right.any()

    lam, converged, eigenvectors = shifted_block_lanczos(mass, factor.solve, shift, satisfied,
                                                         max_columns, stats=stats)
    if state.get("left"):
        return lam, converged, eigenvectors, converged & (lam > right_edge) & (lam <= shift), True
    if state.get("alone"):
        return lam, converged, eigenvectors, converged & (lam > lower) & (lam <= shift), False
    raise SlicingFailed(f"shift {np.sqrt(shift) / (2 * np.pi):.1f} Hz: "
                        f"{np.count_nonzero(converged & (lam > lower) & (lam <= shift))} of "
                        f"{gap_count} eigenvalues converged in {len(lam)} columns")


@dataclass(frozen=True, eq=False)
class ChainStart:
    """Where a chain of shifted runs begins: every eigenvalue ≤ ``lower`` is someone else's
    (``counted`` of them, a certified count), and ``pending`` (k,) ascending with
    ``pending_modes`` (the chain's sink's handle of (n, k) vectors) are converged eigenpairs in
    (lower, right_edge] not yet certified (run 0's, or none)."""

    lower: float
    counted: int
    right_edge: float
    pending: np.ndarray
    pending_modes: object


def slice_chain(mass, factor_at, start, top_omega2, total, sink, slice_modes=80, max_columns=400,
                progress=None):
    """Shifted runs that find every eigenpair in (start.lower, top_omega2] (module docstring).

    factor_at(σ): factor of K − σM with its inertia; total: eigenvalues ≤ top_omega2 (its count).
    ``sink`` (:mod:`sarfe.reduction.mode_sinks`) takes each run's vectors as they are formed and
    keeps the certified eigenpairs gap by gap in ascending order (values (k,), modes (n, k)
    M-normalized); a run's pending vectors go in at once too. Returns the record
    {"shifts", "columns", "negative_pivots", "factorizations"}. Raises SlicingFailed when a gap's
    count is not reached within ``max_columns`` even at a quarter of the width.
    """
    pending, pending_modes = list(np.asarray(start.pending, dtype=float)), start.pending_modes
    lower, counted, right_edge = float(start.lower), int(start.counted), float(start.right_edge)
    record = {"shifts": [], "columns": [], "negative_pivots": [], "factorizations": 0,
              "steps": 0, "mass_products": 0}
    rate = None
    while counted < total:
        known = counted + len(pending)                 # ≈ N(right_edge)
        for retry in range(3):     # a gap the column cap cannot fill: again with half the width
            shift, factor = _place_shift(factor_at, right_edge, known,
                                         max(4, slice_modes // 2 >> retry), top_omega2, total,
                                         rate, record)
            try:
                lam, converged, eigenvectors, take, use_pending = _slice_run(
                    mass, factor, shift, lower, counted, right_edge, pending, max_columns,
                    shift >= top_omega2, record)
                break
            except SlicingFailed:
                if retry == 2:
                    raise
            finally:
                record["shifts"].append(float(shift))
                record["negative_pivots"].append(int(factor.negative_pivots))
                del factor
                # the factor's memory goes before the run's Ritz vectors are formed, so they do
                # not add to the factor and the Krylov store at once (the peak inside the
                # Lanczos steps is unchanged; results bitwise the same: the analysis stays)
                getattr(factor_at, "release", lambda: None)()
        record["columns"].append(int(len(lam)))
        last = shift >= top_omega2
        if use_pending:
            keep_pending = np.count_nonzero(np.asarray(pending) <= shift)   # pending ascend
            if keep_pending:
                sink.keep(np.asarray(pending)[:keep_pending],
                          sink.prefix(pending_modes, keep_pending))
        order = np.flatnonzero(take)
        order = order[np.argsort(lam[order])]
        if len(order):
            sink.keep(lam[order], sink.put(eigenvectors(order)))
        counted = record["negative_pivots"][-1]
        lower = shift
        if progress is not None:
            progress(counted, None)
        if last:
            break
        # run j's converged prefix above the shift carries into the next gap; its edge r_j lies
        # halfway to the first unconverged Ritz value above the shift
        above = np.flatnonzero(lam > shift)
        above = above[np.argsort(lam[above])]
        prefix = np.argmin(converged[above]) if not converged[above].all() else len(above)
        chosen = above[:prefix]
        if prefix < len(above):
            right_edge = 0.5 * (lam[above[prefix - 1]] + lam[above[prefix]]) if prefix else shift
        else:
            right_edge = float(lam[above[-1]]) if len(above) else shift
        pending = list(lam[chosen])
        pending_modes = sink.put(eigenvectors(chosen))
        del eigenvectors             # the run's Krylov store goes before the next one's
        # eigenvalues per rad/s over this run's coverage: the next shift's first guess
        first = np.sqrt(max(lam[order[0]], 0.0)) if len(order) else np.sqrt(shift)
        seen, span = len(order) + len(pending), np.sqrt(right_edge) - first
        rate = seen / span if span > 0 and seen else None
        if right_edge >= top_omega2:
            right_edge = top_omega2
    return record


def sliced_modes(stiffness, mass, cutoff_omega2, found_omega2, found_modes, boundary,
                 slice_modes=80, max_columns=400, progress=None, solver="auto", upper=None,
                 factor_at=None, total=None, sink=None):
    """All eigenpairs of K φ = λ M φ with λ ≤ ``cutoff_omega2`` (module docstring).

    found_omega2 (k,), found_modes: run 0's converged eigenpairs, all λ ≤ ``boundary`` (a value
    between them and run 0's next Ritz value); found_modes is (n, k), or ``sink``'s handle of it
    when a sink is given (:mod:`sarfe.reduction.mode_sinks`; default: in memory). ``upper``: an
    :class:`UpperSlices` already working in a second process; this process then stops at its
    split λ_s and joins it (or does it all when the worker planned no split).
    ``factor_at``/``total``: a :func:`shifted_factorizer` and the count below the cutoff when the
    caller has them. Returns λ (ascending), Φ (Φᵀ M Φ = I) as a list of column blocks in that
    order (no stacked copy of n × n_m; maps of the sinks' files when on disk), and a record
    {"shifts", "columns", "negative_pivots", "factorizations", "modes_below_cutoff"} (with
    "upper": the other process's record, "split", "split_count", and "join_wait_s": wall
    seconds this process waited for the other's block). Raises SlicingFailed when a gap's count
    is not reached (the sink's file is removed).
    """
    sink = MemorySink() if sink is None else sink
    try:
        return _sliced_modes(stiffness, mass, cutoff_omega2, found_omega2, found_modes, boundary,
                             slice_modes, max_columns, progress, solver, upper, factor_at, total,
                             sink)
    except BaseException:
        sink.remove()
        if upper is not None:
            upper.cancel()
        raise


def _sliced_modes(stiffness, mass, cutoff_omega2, found_omega2, found_modes, boundary,
                  slice_modes, max_columns, progress, solver, upper, factor_at, total, sink):
    record = {"factorizations": 0}
    split = None
    if upper is not None:
        try:
            total, split, split_count = upper.plan()
        except SlicingFailed as exc:      # the worker failed placing the split: one chain here
            record["upper_failed"] = str(exc)
        upper = upper if split is not None else None
    if factor_at is None:
        factor_at = shifted_factorizer(stiffness, mass, solver=solver)
    if total is None:
        record["factorizations"] += 1
        factor = factor_at(cutoff_omega2)
        if factor.negative_pivots is None:
            raise SlicingFailed(f"backend {factor.name} reports no inertia")
        total = int(factor.negative_pivots)                     # eigenvalues below the cutoff
        del factor
    top, top_count = (cutoff_omega2, total) if upper is None else (split, split_count)
    found_omega2 = np.asarray(found_omega2, dtype=float)
    covered = int(np.count_nonzero(found_omega2 <= top))
    if boundary >= top and covered == top_count:
        # run 0's converged prefix reaches past the top and holds exactly N(top) values below
        # it (run 0 went on past its cap toward the split): the count certifies them, no shift
        sink.keep(found_omega2[:covered], sink.prefix(found_modes, covered))
        chain = {"shifts": [], "columns": [], "negative_pivots": [], "factorizations": 0,
                 "steps": 0, "mass_products": 0}
    else:
        start = ChainStart(0.0, 0, float(boundary), found_omega2, found_modes)
        chain = slice_chain(mass, factor_at, start, top, top_count, sink, slice_modes,
                            max_columns, progress)
    record.update(chain, factorizations=record["factorizations"] + chain["factorizations"],
                  modes_below_cutoff=int(total))
    upper_values, upper_modes = np.zeros(0), []
    if upper is not None:
        record.update(split=float(split), split_count=int(split_count))
        try:
            waited = time.perf_counter()
            record["cpu_s"] = time.process_time()        # this process's CPU up to the join
            upper_values, upper_modes, record["upper"] = upper.join()
            joined = time.perf_counter()
            record["join_wait_s"] = joined - waited   # idle here (a clock, not a result)
            # the worker's idle: from its last run's end to this process's join (one clock)
            record["upper"]["idle_s"] = max(joined - record["upper"].pop("finished_at"), 0.0)
        except SlicingFailed as exc:      # the worker's part, again in this process
            record["upper_failed"] = str(exc)
            start = ChainStart(split, split_count, split, np.zeros(0),
                               sink.put(np.zeros((mass.shape[0], 0))))
            rest = slice_chain(mass, factor_at, start, cutoff_omega2, total, sink, slice_modes,
                               max_columns, progress)
            record["factorizations"] += rest["factorizations"]
            for key in ("shifts", "columns", "negative_pivots"):
                record[key] = record[key] + rest[key]
    omega2 = np.concatenate([sink.values(), upper_values])
    modes = sink.blocks() + upper_modes
    if np.any(np.diff(omega2) < 0):       # blocks are sorted and follow each other; make sure
        order = np.argsort(omega2)
        return omega2[order], [np.hstack(modes)[:, order]], record
    return omega2, modes, record


def split_count(total, lead):
    """The eigenvalue count N(λ_s) this process's part (0, λ_s] should hold for the two processes
    to finish together: parent cost ≈ run 0 + c·(N(λ_s) − r_0), worker cost ≈ c·(total − N(λ_s))
    with c the cost per mode of a shifted run; run 0 finds r_0 modes for the cost of r_0 − lead
    shifted-run modes, hence N(λ_s) = (total + lead)/2, kept inside [1, total − 1]."""
    return int(min(max(round(0.5 * (total + lead)), 1), total - 1))


def split_shift(factor_at, cutoff_omega2, total, wanted, tolerance=0.02, tries=4):
    """A shift λ_s ≤ cutoff with N(λ_s) ≈ ``wanted`` (within ``tolerance``·total, else the
    closest of ``tries`` tries) and its exact count: (λ_s [rad²/s²], N(λ_s)).

    factor_at(σ): factor of K − σM whose ``negative_pivots`` = N(σ) (Sylvester). First try
    ω = ω_c·wanted/total (N(ω) ≈ a·ω, a plate's modal count in ω); each next one interpolates
    N(ω) linearly between the two counted points around ``wanted`` (from (0, 0), (ω_c, total)
    and the tries so far). The door trim at 5 mm lands within 2 % in two tries; a coarse mesh
    whose count flattens out may take more. Depends on the counts only (never on timing)."""
    omega_c = np.sqrt(cutoff_omega2)
    omegas, counts = [0.0, omega_c], [0, int(total)]
    omega = omega_c * wanted / total
    best = None
    for attempt in range(tries):
        count = int(factor_at(omega ** 2).negative_pivots)
        if best is None or abs(count - wanted) < abs(best[1] - wanted):
            best = (float(omega ** 2), count)
        if abs(count - wanted) <= tolerance * total:
            break
        place = np.searchsorted(counts, count)
        omegas.insert(place, omega)
        counts.insert(place, count)
        omega = float(np.interp(wanted, counts, omegas))
    return best


@dataclass(eq=False)
class UpperSlices:
    """A forked worker process slicing the upper part of the spectrum (:func:`start_upper_slices`).

    ``splits()`` → whether the worker slices the upper part: it counted the eigenvalues below the
    cutoff and found enough to be worth a split (else it has exited). ``plan()`` → (total, lower,
    counted): that count, and the split λ_s with its count N(λ_s) — or (total, None, None)
    without a split. ``join()`` → (λ ascending (k,), Φ as column blocks mapped from the worker's
    file (:class:`~sarfe.reduction.mode_sinks.FileSink`), the worker's record) for
    (λ_s, cutoff], or raises SlicingFailed."""

    process: object
    connection: object
    path: str
    size: int
    _total: tuple | None = None
    _plan: tuple | None = None
    _failed: Exception | None = None

    def _receive(self, kind):
        try:
            message = self.connection.recv()
        except EOFError:
            message = ("error", "the slicing worker died before its counts")
        if message[0] != kind:
            self.cancel()
            raise SlicingFailed(f"upper slices: {message[1]}")
        return message[1:]

    def splits(self):
        if self._total is None:
            self._total = self._receive("count")     # (total, splitting)
            if not self._total[1]:
                self.cancel()
                self._plan = (self._total[0], None, None)
        return self._total[1]

    def plan(self):
        if self._failed is not None:
            raise self._failed
        if self._plan is None and self.splits():
            try:
                self._plan = (self._total[0], *self._receive("plan"))
            except SlicingFailed as exc:
                self._failed = exc
                raise
        return self._plan

    def join(self):
        try:
            status, payload, record, kept = self.connection.recv()
        except EOFError:
            status, payload, record, kept = "error", "the slicing worker died", None, None
        self.process.join()
        self.connection.close()
        if status != "ok":
            _remove(self.path)
            raise SlicingFailed(f"upper slices: {payload}")
        # mapped, not read: the pages are page cache, copied block by block by the caller
        return payload, FileSink(self.size, path=self.path).blocks(kept), record

    def cancel(self):
        if self.process.is_alive():
            self.process.terminate()
        self.process.join()
        self.connection.close()
        _remove(self.path)


def _remove(path):
    try:
        os.remove(path)
    except OSError:
        pass


def start_upper_slices(stiffness, mass, cutoff_omega2, lead, min_total, slice_modes=80,
                       max_columns=400):
    """Fork a worker that counts the eigenvalues below the cutoff and, when there are more than
    ``min_total``, finds every eigenpair in (λ_s, cutoff], N(λ_s) ≈ (total + ``lead``)/2
    (:func:`split_count`, :func:`split_shift`; this process takes (0, λ_s]). K, M are shared
    copy-on-write (fork it before anything large the worker does not need exists, e.g. the
    factor of K_ii: Craig–Bampton forks right after the partition). The modes go to a file in the temporary directory (a
    :class:`~sarfe.reduction.mode_sinks.FileSink`: on disk, not in either process's memory) that
    :meth:`UpperSlices.join` maps and removes. Returns an :class:`UpperSlices`, or None where fork is not available or this
    process is a daemon (a Dask or multiprocessing worker may not have children). The worker's
    results do not depend on timing: the split and its shifts follow from counts alone."""
    import multiprocessing

    if "fork" not in multiprocessing.get_all_start_methods() or \
            multiprocessing.current_process().daemon:      # e.g. a Dask worker: no children
        return None
    path = FileSink(mass.shape[0]).path
    context = multiprocessing.get_context("fork")
    receive, send = context.Pipe(duplex=False)
    process = context.Process(target=_upper_worker, daemon=True,
                              args=(send, stiffness, mass, cutoff_omega2, lead, min_total,
                                    path, slice_modes, max_columns))
    process.start()
    send.close()
    return UpperSlices(process, receive, path, mass.shape[0])


def _upper_worker(connection, stiffness, mass, cutoff_omega2, lead, min_total, path,
                  slice_modes, max_columns):
    """The forked side of :func:`start_upper_slices`: its own PARDISO analysis (the parent's
    instance is not shared), the count below the cutoff (sent at once: this process's run 0
    waits for it), the split by count (sent when placed: this process needs it after run 0),
    then a chain from (λ_s, N(λ_s)) with nothing pending, its vectors appended to ``path`` as
    they are formed (a :class:`~sarfe.reduction.mode_sinks.FileSink`; the kept columns go to
    this process with the values)."""
    try:
        factor_at = shifted_factorizer(stiffness, mass, solver="pardiso")
        counting = {"factorizations": 0}

        def count_at(shift):
            counting["factorizations"] += 1
            return factor_at(shift)

        total = int(count_at(cutoff_omega2).negative_pivots)
        connection.send(("count", total, total > min_total))
        if total <= min_total:
            return
        lower, counted = split_shift(count_at, cutoff_omega2, total, split_count(total, lead))
        connection.send(("plan", lower, counted))
        sink = FileSink(mass.shape[0], path=path)
        start = ChainStart(lower, counted, lower, np.zeros(0), sink.put(np.zeros((sink.rows, 0))))
        record = slice_chain(mass, factor_at, start, cutoff_omega2, total, sink, slice_modes,
                             max_columns)
        record["factorizations"] += counting["factorizations"]    # the counts
        record["cpu_s"] = time.process_time()          # the worker's CPU (a fork starts at 0)
        record["finished_at"] = time.perf_counter()    # CLOCK_MONOTONIC: one clock for both
        omega2 = sink.values()
        if len(omega2) != total - counted or np.any(np.diff(omega2) < 0):
            raise SlicingFailed(f"{len(omega2)} modes for a count of {total - counted}")
        connection.send(("ok", omega2, record, sink.kept()))
    except Exception as exc:  # noqa: BLE001 - reported to the parent, which falls back
        connection.send(("error", f"{type(exc).__name__}: {exc}", None, None))
    finally:
        connection.close()
