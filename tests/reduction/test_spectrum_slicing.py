"""Spectrum slicing in one or two processes against a dense reference (scipy.linalg.eigh).

The model: two copies of the clamped plate, the second 1e-3 stiffer, side by side without
coupling — every eigenvalue comes as a close pair λ, (1 + 1e-3)·λ. One two-process run has its
split λ_s placed inside one pair: the lower process must deliver its lower member, the worker its
upper one, certified by the inertia counts at λ_s. Another places λ_s by count, as a user's run
does (balancing the two processes).
"""
import contextlib
import importlib

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from sarfe.linalg import available_solvers, shifted_factorizer
from sarfe.reduction import craig_bampton, free_dof_positions, node_dofs

STIFFER = 1e-3    # relative spacing of the close pairs


def plate_model(nx, ny):
    """This folder's conftest plate (loaded by path: every test folder has a ``conftest``)."""
    import importlib.util
    from pathlib import Path

    spec = importlib.util.spec_from_file_location("reduction_conftest",
                                                  Path(__file__).with_name("conftest.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.plate_model(nx, ny)

pytestmark = pytest.mark.skipif("pardiso" not in available_solvers(),
                                reason="spectrum slicing needs PARDISO's inertia")


@pytest.fixture(scope="module")
def twin():
    """(K, M, boundary, k_ii, m_ii, reference ω² of (K_ii, M_ii), cutoff [Hz] at twice the
    frequency of a split inside the 120th close pair)."""
    plate = plate_model(12, 8)
    stiffness = sp.block_diag([plate.stiffness, (1 + STIFFER) * plate.stiffness], format="csr")
    mass = sp.block_diag([plate.mass, plate.mass], format="csr")
    one = free_dof_positions(node_dofs(plate.boundary_nodes, (0, 1, 2), plate.dofs_per_node),
                             plate.free_dofs, plate.total_dof_count)
    boundary = np.concatenate([one, one + plate.stiffness.shape[0]])
    interior = np.setdiff1d(np.arange(stiffness.shape[0]), boundary)
    k_ii = stiffness[interior][:, interior].toarray()
    m_ii = mass[interior][:, interior].toarray()
    omega2 = sla.eigh(k_ii, m_ii, eigvals_only=True)
    # the 120th pair: split halfway between its members, cutoff at twice its frequency
    lower = omega2[(omega2 > 0)][2 * 120]
    split = lower * (1 + 0.5 * STIFFER)
    cutoff_hz = 2 * np.sqrt(split) / (2 * np.pi)
    return stiffness, mass, boundary, k_ii, m_ii, omega2, cutoff_hz


@pytest.fixture(scope="module")
def capped():
    """Run 0 capped at 64 columns: the modes above come from spectrum slicing."""
    module = importlib.import_module("sarfe.reduction.fixed_interface_modes")
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(module, "_SLICE_COLUMNS", 64)
        patch.setattr(module, "_SLICE_ENTRIES", 0)
        yield


def reduce(twin, workers):
    stiffness, mass, boundary, *_, cutoff_hz = twin
    return craig_bampton(stiffness, mass, boundary, cutoff_hz=cutoff_hz, residual_vectors=True,
                         workers=workers)


@contextlib.contextmanager
def split_inside_pair(twin):
    """The worker's split at the twin fixture's λ_s (halfway inside the 120th close pair) instead
    of by count; the forked worker inherits the patch."""
    omega2 = twin[5]
    split = (2 * np.pi * twin[6] / 2) ** 2
    slicing = importlib.import_module("sarfe.reduction.spectrum_slicing")
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(slicing, "split_shift",
                      lambda factor_at, cutoff, total, wanted: (split,
                                                                int(factor_at(split).negative_pivots)))
        assert np.count_nonzero(omega2 <= split) % 2 == 1     # inside a pair
        yield


@pytest.fixture(scope="module")
def two(twin, capped):
    with split_inside_pair(twin):
        return reduce(twin, workers=2)


@pytest.fixture(scope="module")
def one(twin, capped):
    return reduce(twin, workers=1)


def check_against_dense(reduced, twin):
    """Every eigenvalue below the cutoff to 1e-9, modes M-orthonormal, K_ii diagonal."""
    _, _, _, k_ii, m_ii, omega2, cutoff_hz = twin
    expected = omega2[omega2 <= (2 * np.pi * cutoff_hz) ** 2]
    assert reduced.mode_count == len(expected) > 200
    np.testing.assert_allclose((2 * np.pi * reduced.mode_frequencies_hz) ** 2, expected, rtol=1e-9)
    phi = reduced.fixed_interface_modes
    np.testing.assert_allclose(phi.T @ m_ii @ phi, np.eye(len(expected)), atol=1e-7)
    np.testing.assert_allclose(phi.T @ k_ii @ phi, np.diag(expected), atol=1e-7 * expected.max())


def test_two_processes_split_inside_a_close_pair(twin, two):
    """The worker takes (λ_s, cutoff], this process the rest; λ_s lies between the two members of
    a pair 1e-3 apart, and the result equals the dense reference."""
    record = two.timings["slicing"]
    assert "upper" in record and "upper_failed" not in record
    omega2 = twin[5]
    inside = np.count_nonzero(omega2 <= record["split"])
    assert omega2[inside - 1] < record["split"] < omega2[inside]
    assert omega2[inside] / omega2[inside - 1] - 1 < 2 * STIFFER      # a close pair
    assert record["split_count"] == inside
    check_against_dense(two, twin)


def test_one_worker_gives_the_same_reduced_model(twin, one, two):
    """workers=1: the whole chain in this process; the same eigenvalues as two processes (to
    1e-12) and as the dense reference, the same reduced model (statics, system eigenvalues)."""
    assert "upper" not in one.timings["slicing"]
    check_against_dense(one, twin)
    np.testing.assert_allclose(one.mode_frequencies_hz, two.mode_frequencies_hz, rtol=1e-12)
    n_b = one.boundary_count
    np.testing.assert_allclose(one.stiffness[:n_b, :n_b], two.stiffness[:n_b, :n_b], rtol=1e-12)
    system = [np.sort(sla.eigh(r.stiffness, r.mass, eigvals_only=True))[:100] for r in (one, two)]
    np.testing.assert_allclose(system[0], system[1], rtol=1e-8)   # as one run vs sliced


def test_falls_back_to_one_process(twin, one, capped, monkeypatch):
    """workers=None on one usable core, or where fork is not available: one process, same modes."""
    slicing = importlib.import_module("sarfe.reduction.spectrum_slicing")
    monkeypatch.setattr(importlib.import_module("sarfe.util.workers"), "available_cpus", lambda: 1)
    single_core = reduce(twin, workers=None)
    assert "upper" not in single_core.timings["slicing"]
    np.testing.assert_allclose(single_core.mode_frequencies_hz, one.mode_frequencies_hz, rtol=1e-12)
    import multiprocessing

    monkeypatch.setattr(multiprocessing, "get_all_start_methods", lambda: ["spawn"])
    stiffness, mass = twin[0], twin[1]
    assert slicing.start_upper_slices(stiffness, mass, 1e8, 0.5, 0) is None   # no worker


def test_two_process_runs_give_the_same_modes(twin, two, capped):
    """Deterministic: the worker's shifts follow from its interval and counts, not from timing."""
    with split_inside_pair(twin):
        again = reduce(twin, workers=2)
    assert again.timings["slicing"]["upper"]["shifts"] == two.timings["slicing"]["upper"]["shifts"]
    np.testing.assert_allclose(again.mode_frequencies_hz, two.mode_frequencies_hz, rtol=1e-13)


def test_split_by_count_gives_the_same_modes(twin, one, capped):
    """As a user's run: the worker places λ_s by count — N(λ_s) within 2 % of the total of the
    balanced count (N(λ_c) + lead)/2 (lead: run 0's head start for its column cap), exact by
    the dense reference — and the modes equal the dense reference and the one-process run."""
    module = importlib.import_module("sarfe.reduction.fixed_interface_modes")
    slicing = importlib.import_module("sarfe.reduction.spectrum_slicing")
    reduced = reduce(twin, workers=2)
    record = reduced.timings["slicing"]
    assert "upper" in record and "upper_failed" not in record
    total = reduced.mode_count
    wanted = slicing.split_count(total, module._RUN0_LEAD_PER_COLUMN * module._SLICE_COLUMNS)
    assert record["split_count"] == np.count_nonzero(twin[5] < record["split"])
    assert abs(record["split_count"] - wanted) <= 0.02 * total
    check_against_dense(reduced, twin)
    np.testing.assert_allclose(reduced.mode_frequencies_hz, one.mode_frequencies_hz, rtol=1e-12)


def test_two_processes_keep_found_vectors_on_disk(twin, one, capped, monkeypatch, tmp_path):
    """Two processes: everything this process found (run 0's prefix, its chain's vectors) and
    Ψ with the residual loads and statics wait in files while both slice — the reduced model is
    the one-process one all the same (modes to 1e-12, statics exactly) — and no file is left."""
    import tempfile

    from sarfe.reduction.mode_sinks import FileSink

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))       # the forked worker's too
    written = []
    put = FileSink.put
    monkeypatch.setattr(FileSink, "put", lambda self, vectors, width=16:
                        written.append(vectors.shape[1]) or put(self, vectors, width))
    reduced = reduce(twin, workers=2)
    record = reduced.timings["slicing"]
    assert "upper" in record and "upper_failed" not in record
    n_b = one.boundary_count
    statics = 3 * n_b                  # Ψ, the loads of unit boundary accelerations F_i, K_ii⁻¹ F_i
    assert sum(written) >= statics + record["split_count"]         # this process's part
    assert not list(tmp_path.iterdir())
    np.testing.assert_allclose(reduced.mode_frequencies_hz, one.mode_frequencies_hz, rtol=1e-12)
    np.testing.assert_array_equal(reduced.interior_basis[:, :n_b], one.interior_basis[:, :n_b])
    np.testing.assert_allclose(reduced.stiffness[:n_b, :n_b], one.stiffness[:n_b, :n_b],
                               rtol=1e-12)


def test_worker_failing_at_its_split_leaves_one_chain(twin, one, capped, monkeypatch, tmp_path):
    """The worker sends its count, then fails placing the split: this process (run 0 already
    done with the worker's count) slices the whole spectrum itself, with the same modes, and
    leaves no file behind."""
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    slicing = importlib.import_module("sarfe.reduction.spectrum_slicing")

    def broken(*args):
        raise RuntimeError("no split")

    monkeypatch.setattr(slicing, "split_shift", broken)          # inherited by the fork
    reduced = reduce(twin, workers=2)
    record = reduced.timings["slicing"]
    assert "upper" not in record and "no split" in record["upper_failed"]
    np.testing.assert_allclose(reduced.mode_frequencies_hz, one.mode_frequencies_hz, rtol=1e-12)
    assert not list(tmp_path.iterdir())


def test_failure_after_the_early_fork_stops_the_worker(twin, capped, monkeypatch, tmp_path):
    """The worker is forked right after the partition, before K_ii is factorized: when the
    factorization fails (a singular K_ii, say) the error reaches the caller, the worker is
    stopped and its file removed."""
    import multiprocessing
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    module = importlib.import_module("sarfe.reduction.craig_bampton")
    modes = importlib.import_module("sarfe.reduction.fixed_interface_modes")
    started = []
    start = modes._start_upper_slices
    monkeypatch.setattr(modes, "_start_upper_slices",
                        lambda *args: started.append(start(*args)) or started[-1])

    def singular(*args, **kwargs):
        raise RuntimeError("singular K_ii")

    monkeypatch.setattr(module, "factorize", singular)
    with pytest.raises(RuntimeError, match="singular K_ii"):
        reduce(twin, workers=2)
    assert started and started[0] is not None              # the worker was running
    assert not started[0].process.is_alive()
    assert started[0].process not in multiprocessing.active_children()
    assert not list(tmp_path.iterdir())


def test_split_shift_hits_the_wanted_count():
    """split_shift from real inertia counts (PARDISO LDLᵀ of K − σM of the plate): the count it
    returns is N(λ_s) of the dense spectrum, within 2 % of the total of the wanted count or the
    closest of its tries, with at most four factorizations; the balanced count stays inside."""
    plate = plate_model(12, 8)
    k, m = plate.stiffness, plate.mass
    omega2 = sla.eigh(k.toarray(), m.toarray(), eigvals_only=True)
    slicing = importlib.import_module("sarfe.reduction.spectrum_slicing")
    factor_at = shifted_factorizer(k, m, solver="pardiso")
    calls = []

    def counting(shift):
        calls.append(shift)
        return factor_at(shift)

    cutoff = 0.5 * (omega2[299] + omega2[300])            # 300 eigenvalues below
    for wanted in (60, 150, 240):
        calls.clear()
        split, count = slicing.split_shift(counting, cutoff, 300, wanted)
        assert count == np.count_nonzero(omega2 < split)
        assert len(calls) <= 4 and split in calls and split < cutoff
        tries = [np.count_nonzero(omega2 < shift) for shift in calls]
        assert abs(count - wanted) <= 0.02 * 300 or abs(count - wanted) == min(
            abs(t - wanted) for t in tries)
    assert slicing.split_count(300, 80) == 190
    assert slicing.split_count(10, 80) == 9 and slicing.split_count(10, -80) == 1


def test_shifted_factorizer_counts_and_solves():
    """One analysis for all shifts: each factor of K − σM counts the eigenvalues below σ (dense
    reference) and solves to round-off; a replaced factor refuses to solve."""
    plate = plate_model(8, 6)
    k, m = plate.stiffness, plate.mass
    omega2 = sla.eigh(k.toarray(), m.toarray(), eigvals_only=True)
    factor_at = shifted_factorizer(k, m, solver="pardiso")
    rhs = np.random.default_rng(0).standard_normal((k.shape[0], 3))
    for shift in (0.5 * omega2[0], 0.5 * (omega2[9] + omega2[10]), 0.5 * (omega2[40] + omega2[41])):
        factor = factor_at(shift)
        assert factor.negative_pivots == np.count_nonzero(omega2 < shift)
        x = factor.solve(rhs)
        assert np.linalg.norm((k - shift * m) @ x - rhs) < 1e-9 * np.linalg.norm(rhs)
    factor_at(omega2[5] * 1.01)
    with pytest.raises(RuntimeError):
        factor.solve(rhs)
    factor_at.release()
    assert factor_at(0.5 * omega2[0]).negative_pivots == 0


def test_partial_reorthogonalization_equals_full_and_dense(twin):
    """A shifted run with partial re-orthogonalization (full passes only where the recurrence
    estimates Q_jᵀ M q > 1e-10) against one with a full pass at every step and the dense
    reference, at a shift inside the twin plates' spectrum (close pairs 1e-3 apart on both
    sides): the same columns and converged eigenvalues (to 1e-12, and the dense ones to 1e-10),
    eigenvectors M-orthonormal to 1e-9 and parallel to the full run's (1 − |cos| ≤ 1e-10, pairs
    1e-3 apart), with fewer full passes than steps."""
    from sarfe.reduction.lanczos import shifted_block_lanczos

    _, _, _, k_ii, m_ii, omega2, _ = twin
    stiffness, mass = sp.csr_matrix(k_ii), sp.csr_matrix(m_ii)
    shift = 0.5 * (omega2[151] + omega2[152])            # between two pairs
    factor = shifted_factorizer(stiffness, mass, solver="pardiso")(shift)
    runs = {}
    for partial in (False, True):
        stats = {}
        lam, converged, vectors = shifted_block_lanczos(
            mass, factor.solve, shift, lambda lam, converged: converged.sum() >= 80, 400,
            stats=stats, partial=partial)
        chosen = np.flatnonzero(converged)
        chosen = chosen[np.argsort(lam[chosen])]
        runs[partial] = lam[chosen], vectors(chosen), stats, len(lam)
    (full_lam, full_phi, full_stats, full_columns), (lam, phi, stats, columns) = runs[False], \
        runs[True]
    assert columns == full_columns and len(lam) == len(full_lam) >= 80
    assert full_stats["full_passes"] == full_stats["steps"]
    assert stats["full_passes"] < 0.8 * stats["steps"]
    np.testing.assert_allclose(lam, full_lam, rtol=1e-12)
    nearest = omega2[np.abs(omega2[None, :] - lam[:, None]).argmin(axis=1)]
    np.testing.assert_allclose(lam, nearest, rtol=1e-10)
    assert len(np.unique(nearest)) == len(lam)                     # none found twice
    np.testing.assert_allclose(phi.T @ m_ii @ phi, np.eye(len(lam)), atol=1e-9)
    cosines = np.abs(np.einsum("ij,ij->j", full_phi, m_ii @ phi))
    np.testing.assert_allclose(cosines, 1.0, atol=1e-10)


def test_run0_goes_on_to_a_split_just_above_its_yield(twin, one, capped):
    """A split a few modes above what run 0 finds at its cap: run 0 goes on past the cap (at most
    _RUN0_EXTENSION of it) until its converged prefix holds every mode below λ_s, certified by
    the worker's count N(λ_s) — no shifted run nor factorization in this process — and the
    modes equal the dense reference. Both processes' CPU and the worker's idle time are recorded."""
    omega2 = twin[5]
    positive = omega2[omega2 > 0]
    yielded = one.timings["slicing"]["run0_modes"]             # run 0's converged prefix at the cap
    pair = (yielded + 2) // 2                                  # a close pair just above it
    split = positive[2 * pair] * (1 + 0.5 * STIFFER)
    slicing = importlib.import_module("sarfe.reduction.spectrum_slicing")
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(slicing, "split_shift",
                      lambda factor_at, cutoff, total, wanted: (split,
                                                                int(factor_at(split).negative_pivots)))
        reduced = reduce(twin, workers=2)
    record = reduced.timings["slicing"]
    assert record["split_count"] == np.count_nonzero(omega2 <= split) > yielded
    assert record["run0_extended_to_split"] == record["split_count"]
    assert record["shifts"] == [] and record["factorizations"] == 0
    extension = importlib.import_module("sarfe.reduction.fixed_interface_modes")._RUN0_EXTENSION
    assert 64 < record["run0_columns"] <= 64 * (1 + extension)
    assert record["upper"]["cpu_s"] > 0 and record["upper"]["idle_s"] >= 0 and record["cpu_s"] > 0
    check_against_dense(reduced, twin)
