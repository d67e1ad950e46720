"""A case without contacts at the default resolution ('auto') is linear: no H search (it used to
crash reshaping an empty contact set), and its level is the modal sum's closed form."""
import json

import numpy as np
import pytest
import yaml
from small_cases import TINY

from sarfe.cli import main


def no_contact_case() -> str:
    """:data:`small_cases.TINY` without its contact and solver section (resolution 'auto'), with
    modal ζ 0.02 and the ERP's air stated (the closed form below uses them)."""
    data = yaml.safe_load(TINY)
    del data["contacts"], data["solver"]
    data.update(name="nocontact", damping={"modal_zeta": 0.02}, output={"files": ["summary"]})
    data["erp"].update(rho_kg_m3=1.2, c_m_s=340.0)
    return yaml.safe_dump(data, sort_keys=False)


def test_no_contacts_at_auto_resolution_is_the_modal_sum(tmp_path, capsys):
    case = tmp_path / "case.yaml"
    case.write_text(no_contact_case())
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
