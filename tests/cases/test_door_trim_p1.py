"""cases/door_trim_p1.yaml (issue 15, P1): ≥ 12 contact pairs of both kinds on the generator's
spots, H = 15, a sweep; its groups resolve on a coarse mesh of the same generator parameters."""
from pathlib import Path

from sarfe.pipeline import load_case
from sarfe.pipeline.checks.mesh_checks import check_mesh

CASE = Path(__file__).resolve().parents[2] / "cases" / "door_trim_p1.yaml"


def test_p1_case_contacts_and_settings():
    case = load_case(CASE)
    kinds = [c["type"] for c in case.data["contacts"]]
    assert len(kinds) >= 12 and {"rattle", "squeak"} <= set(kinds)
    assert case.data["solver"]["harmonics"] == 15
    assert case.data["solver"]["error_estimate"] and case.data["solver"]["stability"]
    assert "sweep" in case.data["excitation"]
    assert case.data["model"]["fe"]["generator"]["mesh_size_m"] == 0.005


def test_p1_case_pairs_resolve_on_a_coarse_mesh():
    data = load_case(CASE).data
    data["model"]["fe"]["generator"]["mesh_size_m"] = 0.03
    info = check_mesh(load_case(data, base_dir=CASE.parent))
    assert len(info["contact_pairs"]) >= 12
    assert all(n == 1 for n in info["contact_pairs"].values())   # one node pair per spot
