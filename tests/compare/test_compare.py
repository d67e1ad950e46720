"""``sarfe compare``: a result against itself gives zero deltas; two friction coefficients of the
squeak rig give exactly the level differences of the two separate solves; bad input exits 2."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
import yaml

from sarfe.cli import main
from sarfe.compare.deltas import all_deltas
from sarfe.pipeline import load_case, solve_case

FREQUENCIES_HZ = [100.0, 150.0]


def squeak_case(tmp_path, mu: float):
    """cases/squeak_rig.yaml at two frequencies with H = 7, no stability/error pass, three files (fast), friction coefficient ``mu``."""
    data = yaml.safe_load(open("cases/squeak_rig.yaml"))
    data["name"] = f"squeak_mu{mu:g}"
    data["contacts"][0]["friction_coefficient"] = mu
    data["excitation"]["frequency_hz"] = FREQUENCIES_HZ
    data["solver"] = {"harmonics": 7, "samples_per_period": 64, "stability": False,
                      "error_estimate": False}
    data["output"] = {"files": ["summary", "response", "erp_vtu"]}
    path = tmp_path / f"squeak_mu{mu:g}.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.fixture(scope="module")
def two_mu(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("compare")
    out = {}
    for mu in (0.3, 0.15):
        folder = tmp / f"mu{mu:g}"
        solve_case(load_case(squeak_case(tmp, mu)), output_dir=folder)
        out[mu] = folder
    return tmp, out


def test_result_against_itself_is_zero(two_mu, capsys):
    tmp, folders = two_mu
    a = folders[0.3]
    assert main(["compare", str(a), str(a), "-o", str(tmp / "aa"), "--quiet"]) == 0
    data = json.loads((tmp / "aa" / "compare.json").read_text())
    (c,) = data["comparisons"]
    assert c["worst_delta_dba"] == 0.0
    assert len(c["points"]) == len(FREQUENCIES_HZ)
    deltas = all_deltas(c["points"])
    assert len(deltas) > 3 * len(FREQUENCIES_HZ)       # totals, contact, bands, sources
    assert all(d is not None and abs(d) < 1e-12 for d in deltas)
    (m,) = data["maps"]
    assert m["available"] and m["delta_max_db"] == 0.0 and m["delta_min_db"] == 0.0
    assert (tmp / "aa" / "compare.html").is_file()


def test_two_friction_coefficients_give_the_difference_of_the_solves(two_mu):
    tmp, folders = two_mu
    out = tmp / "mu"
    assert main(["compare", str(folders[0.3]), str(folders[0.15]), "-o", str(out), "--quiet"]) == 0
    data = json.loads((out / "compare.json").read_text())
    s_a = json.loads((folders[0.3] / "summary.json").read_text())
    s_b = json.loads((folders[0.15] / "summary.json").read_text())
    (c,) = data["comparisons"]
    for p, pa, pb in zip(c["points"], s_a["points"], s_b["points"]):
        expected = pb["erp"]["level_dba"] - pa["erp"]["level_dba"]
        assert p["delta_dba"] == pytest.approx(expected, abs=1e-12)
        (rub,) = p["contacts"]
        assert rub["delta_dba"] == pytest.approx(
            pb["contacts"][0]["erp_level_dba"] - pa["contacts"][0]["erp_level_dba"], abs=1e-12)
        bands_a = dict(zip(pa["bands"]["nonlinear"]["nominal_hz"], pa["bands"]["nonlinear"]["level_dba"]))
        bands_b = dict(zip(pb["bands"]["nonlinear"]["nominal_hz"], pb["bands"]["nonlinear"]["level_dba"]))
        for band in p["bands"]:
            la, lb = bands_a[band["nominal_hz"]], bands_b[band["nominal_hz"]]
            if la is not None and lb is not None:
                assert band["delta_dba"] == pytest.approx(lb - la, abs=1e-12)
    assert c["worst_delta_dba"] == pytest.approx(
        s_b["worst"]["erp_level_dba"] - s_a["worst"]["erp_level_dba"], abs=1e-12)
    # halving μ changes the squeak (stick–slip) response: a real, non-zero difference
    assert max(abs(p["delta_dba"]) for p in c["points"]) > 0.1
    assert data["maps"][0]["available"]          # same mesh: a difference map is drawn
    assert (out / "compare_map_1.png").is_file()


def test_bad_input_one_line_exit_2(two_mu, tmp_path, capsys):
    _, folders = two_mu
    (tmp_path / "notes").mkdir()
    for bad in (tmp_path / "missing", tmp_path / "notes"):
        assert main(["compare", str(folders[0.3]), str(bad), "-o", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and str(bad) in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()                  # nothing written
