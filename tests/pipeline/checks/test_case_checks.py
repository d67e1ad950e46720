"""Inputs that are not errors but far outside a plausible model: each gets one warning line (never
a silent change of the model), and nothing numpy says leaks to stderr (review8 items 4 and 6-7)."""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml

from sarfe.case.read import CaseLoader, load_case

ROOT = Path(__file__).resolve().parents[3]
CASES = ROOT / "cases"


def squeak() -> dict:
    return yaml.load((CASES / "squeak_rig.yaml").read_text(), Loader=CaseLoader)


def rig() -> dict:
    return yaml.load((CASES / "rattle_rig.yaml").read_text(), Loader=CaseLoader)


def checked(data, tmp_path):
    from sarfe.pipeline.checks.case_checks import check_case

    path = tmp_path / "case.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return check_case(load_case(path), write=False)


def test_sweep_plot_of_zero_power_points_raises_no_numpy_warning():
    """A sweep whose every level is −inf dB (zero radiated power): no jump is found and numpy's
    'invalid value encountered in subtract' does not reach stderr."""
    from sarfe.results.plots import jump_starts

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert not jump_starts(np.full(5, -np.inf)).any()
        assert jump_starts(np.array([10.0, 10.5, 40.0, 40.2]))[2]


def test_force_partly_on_fixed_nodes_warns_with_the_share_lost(tmp_path):
    """A force on the whole beam (element group part_beam) whose clamp_beam nodes are fixed: F/n
    per node, so the k clamped of n nodes put k/n of force_N into the supports — a warning
    stating k, n and k/n (the model is not changed); all nodes fixed is an error."""
    from sarfe.pipeline.model.case_mesh import load_case_mesh
    from sarfe.pipeline.model.groups import resolve_node_group

    data = rig()
    assert not [w for w in checked(data, tmp_path).warnings if "supports" in w]
    data["excitation"]["forces"][0]["group"] = "part_beam"
    found = [w for w in checked(data, tmp_path).warnings if "supports" in w]
    case = load_case(tmp_path / "case.yaml")
    mesh = load_case_mesh(case)
    beam = resolve_node_group(case, mesh, "part_beam", ())
    clamp = resolve_node_group(case, mesh, "clamp_beam", ())
    k, n = len(np.intersect1d(beam, clamp)), len(beam)
    assert 0 < k < n
    assert found == [f"excitation.forces[0]: {k} of the {n} nodes of group part_beam are fixed: "
                     f"{100 * k / n:.3g} % of force_N = 0.05 N goes straight into the supports"]
    data["excitation"]["forces"][0]["group"] = "clamp_beam"
    with pytest.raises(Exception, match=r"excitation\.forces\[0\]\.group: the force on group "
                                        "clamp_beam acts on no free DOF"):
        checked(data, tmp_path)


def test_matrices_model_held_only_by_closed_contacts(tmp_path):
    """Two masses, DOF 1 on a ground spring, DOF 0 free except for a contact to DOF 1 (w = u0 − u1).
    K alone is singular (rank 1). An open rattle gap (g > 0) adds no static spring: not held, null
    space 1 naming DOF 0. The same contact preloaded is closed at rest: K + k_n (e0 − e1)(e0 − e1)ᵀ
    is regular, and the case passes."""
    from sarfe.case.errors import CaseError

    data = {"name": "floating", "model": {"matrices": {"mass": [[1.0, 0.0], [0.0, 1.0]],
                                                       "stiffness": [[0.0, 0.0], [0.0, 1.0e4]]}},
            "damping": {"modal_zeta": 0.02},
            "contacts": [{"name": "c", "type": "rattle", "normal_dof": {"dof": 0, "relative_to": 1},
                          "gap_m": 1e-4, "normal_stiffness_N_m": 1e5}],
            "excitation": {"forces": [{"dof": 1, "force_N": 1.0}], "frequency_hz": [20.0]},
            "solver": {"harmonics": 3, "samples_per_period": 64},
            "erp": {"dofs": [1], "areas_m2": [0.01]}}
    with pytest.raises(CaseError, match=r"model\.matrices\.stiffness: the structure is not held.*"
                                        r"null space of size 1 of 2 DOFs; DOF\(s\) 0 move"):
        checked(data, tmp_path)
    del data["contacts"][0]["gap_m"]
    data["contacts"][0]["preload_N"] = 5.0
    assert checked(data, tmp_path).warnings == ()


def test_mode_count_above_the_interior_warns_with_the_clip(tmp_path):
    """reduction.mode_count = 100000 on the squeak rig: validate states the clip with the interior
    DOF count, which equals the linear stage's free − boundary DOFs (built with 5 modes); a
    reduction that kept fewer modes than asked (within the interior) warns after the reduction."""
    from types import SimpleNamespace

    from sarfe.pipeline.checks.case_checks import reduced_model_warnings
    from sarfe.pipeline.model.linear_stage import build_linear_model

    data = squeak()
    data["reduction"] = {"mode_count": 5}
    assert not [w for w in checked(data, tmp_path).warnings if "mode_count" in w]
    info = build_linear_model(load_case(tmp_path / "case.yaml")).info
    interior = info["free_dofs"] - info["boundary_dofs"]
    data["reduction"] = {"mode_count": 100000}
    found = [w for w in checked(data, tmp_path).warnings if "mode_count" in w]
    assert len(found) == 1 and f"100000 asked, at most {interior} available" in found[0]
    stage = SimpleNamespace(kind="fe", mode_frequencies_hz=np.array([1e3, 1e4]),   # above H·f_max
                            info={"modes": 2, "free_dofs": 100, "boundary_dofs": 10})
    assert reduced_model_warnings(load_case(tmp_path / "case.yaml"), stage) == []   # said before
    data["reduction"] = {"mode_count": 50}
    checked(data, tmp_path)
    assert reduced_model_warnings(load_case(tmp_path / "case.yaml"), stage)[0] == (
        "reduction.mode_count = 50: the reduction kept 2 modes (50 asked, 2 available from 90 "
        "interior DOFs)")


@pytest.mark.parametrize("gap, warned", [(5e-4, False), (-5e-4, False), (0.02, False),
                                         (0.1, True), (-0.1, True), (-0.5, True)])
def test_gap_far_above_the_shell_thickness_warns(tmp_path, gap, warned):
    """Rule: |gap_m| > 10 × max(thickest shell, tolerance_m) warns — on the rattle rig (shells
    2.5 mm, tolerance 0.1 mm, 0.287 m across) above 25 mm: ±0.1 and −0.5 (an overclosure beyond
    the structure's size) do, ±0.5 mm and 20 mm do not. The case is not changed."""
    data = rig()
    data["contacts"][0]["gap_m"] = gap
    found = [w for w in checked(data, tmp_path).warnings if "gap_m" in w]
    assert bool(found) == warned, found
    if warned:
        assert found[0].startswith(f"contacts[0] (tip): gap_m = {gap:g} m is ")
        assert "10 × the thickest shell, thickness_m = 0.0025 m" in found[0]
        assert ("overclosure" in found[0]) == (gap < 0)
    assert load_case(tmp_path / "case.yaml").config.contacts[0].gap_m == gap


def test_gap_of_a_matrices_contact_is_judged_by_its_tolerance(tmp_path):
    """Without shells the reference is tolerance_m: lumped_rattle (2e-5 m) warns above 2e-4 m;
    its own 1e-4 m does not."""
    data = yaml.load((CASES / "lumped_rattle.yaml").read_text(), Loader=CaseLoader)
    assert checked(data, tmp_path).warnings == ()
    data["contacts"][0]["gap_m"] = 0.01
    (found,) = checked(data, tmp_path).warnings
    assert "its tolerance_m = 2e-05 m" in found and "open gap" in found
