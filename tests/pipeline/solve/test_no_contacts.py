"""A case without contacts at the default resolution ('auto') is linear: no H search (it used to
crash reshaping an empty contact set), and its level is the modal sum's closed form."""
import json

import numpy as np
import pytest

from sarfe.cli import main

CASE = """\
name: nocontact
model:
  matrices:
    mass: [[1.0, 0.0], [0.0, 1.0]]
    stiffness: [[2.0e+4, -1.0e+4], [-1.0e+4, 2.0e+4]]
damping: {modal_zeta: 0.02}
excitation:
  forces: [{dof: 0, force_N: 1.0}]
  frequency_hz: [20.0]
erp: {dofs: [0], areas_m2: [0.01], rho_kg_m3: 1.2, c_m_s: 340.0}
output: {files: [summary]}
"""


def test_no_contacts_at_auto_resolution_is_the_modal_sum(tmp_path, capsys):
    case = tmp_path / "case.yaml"
    case.write_text(CASE)
    assert main(["solve", str(case), "--output", str(tmp_path / "out")]) == 0
    assert "no contacts: the response is linear" in capsys.readouterr().err
    point = json.loads((tmp_path / "out" / "summary.json").read_text())["points"][0]
    omega = 2 * np.pi * 20.0
    phi = np.array([[1.0, 1.0], [1.0, -1.0]]) / np.sqrt(2.0)     # mass-normalised modes
    w = np.sqrt([1.0e4, 3.0e4])
    q = phi[0] * 1.0 / (w**2 - omega**2 + 2j * 0.02 * w * omega)
    v = 1j * omega * (phi[0] @ q)
    power = 0.5 * 1.2 * 340.0 * 0.01 * abs(v) ** 2
    assert point["erp"]["power_W"] == pytest.approx(power, rel=1e-9)
    assert point["erp"]["level_db"] == pytest.approx(point["linear"]["erp_level_db"], abs=1e-9)
