"""response.h5's time record is bounded by H, not by the N a sweep raised (issue 30 item 3).

A 1-DOF impact oscillator (0.2 kg on 2·10⁴ N/m, ζ = 3 %, a wall 0.1 mm away at k_n = 10⁸ N/m,
driven with 2 N at 60–72 Hz: it impacts), solved by HBM at H = 7 with N raised to 4096 (what
the continuation does at hard contacts; the case's N is 256), its histories also at 256 and 1024. The record must:
not grow with N (within 3 % between 1024 and 4096, against a 4× larger full-N history), hold
the solution's harmonics exactly, and keep the full-N peak contact force — the maximum of the
force's own AFT samples, which a plain decimation misses — to 1e-12; the per-bin state must say
"closed at any time in the bin". run_cost's disk estimate for that record is within ×1.5 of
the bytes written.
"""
from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest

from sarfe.case.read import load_case
from sarfe.hbm import solve_frequency
from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.model import make_linear_model
from sarfe.hbm.residual import nonlinear_force
from sarfe.pipeline import solve_case
from sarfe.pipeline.checks.run_cost import ModelSize, file_bytes
from sarfe.results import read_response_h5, write_response_h5
from sarfe.results.response_h5 import record_samples
from tests.small_cases import TINY

MASS, SPRING, GAP, NORMAL_STIFFNESS = 0.2, 2e4, 1e-4, 1e8
H, BASE_N, SOLVED_N = 7, 256, 4096
FREQUENCIES_HZ = np.linspace(60.0, 72.0, 4)
PEAK_TOLERANCE = 1e-12          # the record's peak force against the full-N AFT samples' maximum


def oscillator():
    model = make_linear_model(np.eye(1) * MASS, np.eye(1) * 0.06 * np.sqrt(SPRING * MASS),
                              np.eye(1) * SPRING)
    contacts = make_contact_set(np.eye(1), ["rattle"], [0], [[-1, -1]], gap=GAP,
                                normal_stiffness=NORMAL_STIFFNESS, names=["stop"])
    F = np.zeros((2 * H + 1, 1))
    F[1, 0] = 2.0
    return model, contacts, F


@functools.cache
def sweep(N):
    """HBM solutions at FREQUENCIES_HZ solved with the raised N = 4096 (warm-started, converged),
    their contact time histories at ``N`` by the AFT of their harmonics — what
    sarfe.pipeline.solve.points.common_samples does to a sweep's points solved with another N."""
    model, contacts, F = oscillator()
    out, previous = [], None
    for f in FREQUENCIES_HZ:
        s = solve_frequency(model, contacts, F, 2 * np.pi * f, H, SOLVED_N,
                            initial=None if previous is None else previous.displacement)
        assert s.converged, (f, s.reason)
        out.append(s)
        previous = s
    if N != SOLVED_N:
        out = [dataclasses.replace(s, samples_per_period=N, contact_force_time=r.force_time,
                                   contact_state=r.state)
               for s in out for r in [nonlinear_force(contacts, s.displacement, N,
                                                      jacobian=False)[2]]]
    return contacts, out


def written(tmp_path, N):
    contacts, sols = sweep(N)
    path = write_response_h5(tmp_path / f"n{N}.h5", sols, contacts=contacts,
                             base_samples_per_period=BASE_N)
    return path, sols


def test_record_size_does_not_grow_with_the_raised_N(tmp_path):
    """N_rec = 256 for H = 7 at the case's N = 256; the files at N = 1024 and 4096 are the same
    size within 3 % although their full histories differ 4×, and no larger than ×1.5 the base."""
    assert record_samples(H, 4096, BASE_N) == record_samples(H, 1024, BASE_N) == BASE_N
    assert record_samples(H, 128, BASE_N) == 128           # never more than the solve's N
    assert record_samples(30, 1 << 15) == 512               # 2^⌈log₂ 16 H⌉ without a base
    assert record_samples(7, 1000, 256) == 250              # a divisor of N: a clean decimation
    sizes = {N: written(tmp_path, N)[0].stat().st_size for N in (BASE_N, 1024, 4096)}
    assert sizes[4096] == pytest.approx(sizes[1024], rel=0.03)
    assert sizes[4096] < 1.5 * sizes[BASE_N]
    full_history = len(FREQUENCIES_HZ) * 4096 * 8
    assert sizes[4096] < full_history                       # the old layout held this much more
    data = read_response_h5(written(tmp_path, 4096)[0])
    assert data["attrs"]["samples_per_period"] == 4096
    assert data["attrs"]["record_samples_per_period"] == BASE_N
    assert data["attrs"]["record_decimation"] == 16 and data["attrs"]["format_version"] == 3


def test_record_keeps_harmonics_peak_force_and_contact_state(tmp_path):
    """/contacts/force_N and displacement_m are the solution's harmonics (exact); force_time_N is
    every 16th AFT sample; the largest force_peak_N is the largest force of the 4096 AFT samples
    (PEAK_TOLERANCE), which the decimated samples alone miss; state per bin = closed at any time."""
    path, sols = written(tmp_path, 4096)
    c = read_response_h5(path)["contacts"]
    step = 4096 // BASE_N
    missed = []
    for j, s in enumerate(sols):
        np.testing.assert_array_equal(c["force_N"][j], s.contact_force)
        np.testing.assert_array_equal(c["displacement_m"][j], s.contact_displacement)
        force = np.asarray(s.contact_force_time)
        np.testing.assert_array_equal(c["force_time_N"][j], force[::step])
        peak = np.max(np.abs(force))
        assert peak > 0                                      # it impacts
        assert np.max(np.abs(c["force_peak_N"][j])) == pytest.approx(peak, rel=PEAK_TOLERANCE)
        missed.append(1 - np.max(np.abs(c["force_time_N"][j])) / peak)
        closed = np.asarray(s.contact_state).reshape(BASE_N, step, -1).max(axis=1)
        np.testing.assert_array_equal(c["state"][j], closed)
        assert np.count_nonzero(c["state"][j]) >= np.count_nonzero(
            np.asarray(s.contact_state)[::step])             # a short closure is never lost
    assert max(missed) > 1e-3      # a decimation alone would understate the impact force


def test_run_cost_estimates_the_record_of_a_run(tmp_path):
    """run_cost's response.h5 bytes against a real run's file (the 2-DOF rattle at 3 listed
    frequencies, every per-point record of the pipeline): within ×1.5; and its estimate at a
    raised N is the one at the case's N (the record is bounded: not ∝ the raised N)."""
    path = tmp_path / "tiny.yaml"
    path.write_text(TINY.replace("output: {files: [summary, table]}", "output: {files: [response]}")
                    .replace("frequency_hz: [20.0]", "frequency_hz: [15.0, 20.0, 25.0]"))
    result = solve_case(path, output_dir=tmp_path / "out")
    real = (tmp_path / "out" / "response.h5").stat().st_size
    estimate = result.summary["cost_estimate"]["files"]["response.h5"][0]
    assert real / 1.5 < estimate < 1.5 * real
    config = load_case(path).config
    size = ModelSize(dofs=2, radiating_nodes=1, contacts=1, contact_rows=1)
    N = config.solver.samples_per_period
    assert file_bytes(config, size, 1000, 3, 64 * N, N)["response.h5"] == pytest.approx(
        file_bytes(config, size, 1000, 3, N, N)["response.h5"], rel=0.05)
