"""`sarfe verify`: every harmonic up to H, contact and ERP rows and the stability verdict, each with
its tolerance, against time integration (1-DOF rattle oscillator hitting a stop)."""
import pytest

from sarfe.cli import main

CASE = """\
name: osc
model:
  matrices: {{mass: [[0.5]], stiffness: [[2.0e4]]}}
damping: {{modal_zeta: 0.05}}
contacts:
  - {{name: stop, type: rattle, normal_dof: 0, gap_m: {gap}, normal_stiffness_N_m: 1.0e5}}
excitation:
  forces: [{{dof: 0, force_N: 1.0}}]
  frequency_hz: 20.0
solver: {{harmonics: 7, samples_per_period: 128}}
"""


def test_verify_checks_every_harmonic_erp_and_stability(tmp_path, capsys):
    """Amplitude 8.3e-5 m against a 5e-5 m gap: impacts every period; HBM (H = 7) and Newmark agree
    on all 7 harmonics within 5 % of the first, and both call the orbit stable."""
    path = tmp_path / "osc.yaml"
    path.write_text(CASE.format(gap=5.0e-5))
    code = main(["verify", str(path), "--frequency-hz", "20", "--quiet"])
    out = capsys.readouterr().out
    assert code == 0, out
    for k in range(1, 8):
        assert f"harmonic {k}:" in out
    assert "ERP total [dB(A)]" in out and "≤ 0.5 dB" in out and "≤ 5 %" in out
    stability = [line for line in out.splitlines() if line.startswith("stability")]
    assert len(stability) == 1 and stability[0].split()[-1] == "yes"
    assert "stable       stable" in stability[0]
    assert "agree: every comparison within its tolerance" in out


def test_verify_tolerance_flags_a_difference(tmp_path, capsys):
    path = tmp_path / "osc.yaml"
    path.write_text(CASE.format(gap=5.0e-5))
    code = main(["verify", str(path), "--frequency-hz", "20", "--quiet", "--tolerance", "1e-7"])
    out = capsys.readouterr().out
    assert code == 3 and "DIFFER" in out and " NO" in out
