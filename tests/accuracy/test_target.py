"""The accuracy target a user gives (sarfe.accuracy.target): presets, dicts and 'key=value' text,
the amplitude budget of an ERP target (ε_dB → 10^{ε_dB/20} − 1), one clear error for bad input."""
import pytest

from sarfe.accuracy.target import AccuracyTarget, parse_accuracy


def test_parse_accuracy():
    assert parse_accuracy("fast").amplitude_rel == 5e-2
    assert parse_accuracy({"erp_db": 0.5}).erp_db == 0.5
    assert parse_accuracy("amplitude_rel=1e-3").amplitude_rel == 1e-3
    assert AccuracyTarget(erp_db=0.5).amplitude_budget() == pytest.approx(10 ** (0.5 / 20) - 1)
    for bad in ("medium", {"erp": 1}, {"erp_db": -1}, {"erp_db": float("nan")}, 3):
        with pytest.raises(ValueError):
            parse_accuracy(bad)


def test_met_by_checks_every_given_target_within_the_share():
    target = parse_accuracy("balanced")           # 1 %, 0.5 dB
    assert target.met_by(0.004, 0.2, share=0.5)
    assert not target.met_by(0.006, 0.2, share=0.5)
    assert not target.met_by(0.004, -0.3, share=0.5)     # |ΔL| counts
    assert AccuracyTarget().met_by(0.009, 10.0)           # no target: the balanced amplitude budget
