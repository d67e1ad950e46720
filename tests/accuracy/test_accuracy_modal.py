"""The modal part of the per-point error estimate, (4)–(5) of sarfe.accuracy.modal_truncation: two probes
(the top 1/20 and 1/5 of the modes left out) and the decay p of an error ∝ m^{−p} fitted from both.
Closed forms: for a truncation error e(m) = C m^{−p} the probes change by d_i = e(m'_i) − e(m) and
the extrapolation returns e(m) exactly while 1 ≤ p ≤ 2.5, more than e(m) (never less) for faster
decays, and p = 1 (the slowest plate-like decay: the earlier single probe, top fifth × 4, which it
never exceeds) when the changes do not decay."""
import numpy as np
import pytest

from sarfe.accuracy.modal_truncation import (MODE_DECAY, MODE_PROBES, mode_decay,
                                             mode_richardson, modal_extrapolation)

MODES = 317          # door trim, 15 mm, cutoff H f_max (benchmarks/results/cutoff.md)


def _probes(p, scale=1e-3):
    coarser = [MODES - max(1, int(MODES * q)) for q in MODE_PROBES]
    error = (lambda m: scale * (m / MODES) ** (-p))
    return coarser, [error(m) - error(MODES) for m in coarser], error(MODES)


@pytest.mark.parametrize("p", [1.0, 1.5, 2.0, 2.5])
def test_extrapolation_recovers_a_power_law_error(p):
    coarser, changes, error = _probes(p)
    assert mode_decay(MODES, coarser, changes) == pytest.approx(p, abs=1e-9)
    estimate, fitted = modal_extrapolation(MODES, coarser, changes)
    assert estimate == pytest.approx(error, rel=1e-8) and fitted == pytest.approx(p, abs=1e-9)


@pytest.mark.parametrize("p", [3.0, 5.0, 8.0])
def test_faster_decay_is_over_reported_never_under(p):
    coarser, changes, error = _probes(p)
    estimate, fitted = modal_extrapolation(MODES, coarser, changes)
    assert fitted == MODE_DECAY[1]
    # the cap's price: 1.3× at p = 3, 2.7× at 5, 6.6× at 8 (≈ the decay measured from 0.75 to 1.0 H f_max)
    assert error < estimate < 7.0 * error


def test_changes_that_do_not_decay_use_the_slowest_decay():
    coarser = [MODES - max(1, int(MODES * q)) for q in MODE_PROBES]
    # the smaller probe changed more than the larger (a resonance near the cutoff): p = 1 on the
    # larger probe, the top fifth × m'/(m − m') ≈ 4
    estimate, fitted = modal_extrapolation(MODES, coarser, [2e-4, 1e-4])
    assert fitted == 1.0
    assert estimate == pytest.approx(1e-4 * coarser[1] / (MODES - coarser[1]))     # m'/(m − m')
    assert mode_richardson(MODES, coarser[1]) == pytest.approx(coarser[1] / (MODES - coarser[1]))


@pytest.mark.parametrize("changes", [[1e-4, 1e-3], [1e-4, 2e-4], [3e-4, 1e-4], [1e-9, 1e-3]])
def test_never_above_the_single_top_fifth_probe(changes):
    coarser = [MODES - max(1, int(MODES * q)) for q in MODE_PROBES]
    estimate, _ = modal_extrapolation(MODES, coarser, changes)
    assert estimate <= changes[1] * mode_richardson(MODES, coarser[1], 1.0) * (1 + 1e-12)


def test_one_probe_or_equal_probes_fall_back_to_p_1():
    estimate, fitted = modal_extrapolation(10, [9], [1e-3])
    assert fitted == 1.0 and estimate == pytest.approx(9e-3)
    estimate, fitted = modal_extrapolation(8, [7, 7], [1e-3, 1e-3])    # few modes: same probe twice
    assert fitted == 1.0 and estimate == pytest.approx(7e-3)
    assert np.isfinite(estimate)
