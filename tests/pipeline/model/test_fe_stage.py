"""The mesh/generator path of the linear stage (sarfe.pipeline.model.fe_stage): each kind of
Craig–Bampton failure is said with its cause (review8 item 8: not always 'the structure is not
held'), and the steps of the stage against closed forms on the rattle rig."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from sarfe.case.read import CaseLoader, load_case

ROOT = Path(__file__).resolve().parents[3]


def test_craig_bampton_failures_say_their_cause():
    """Singular K_ii (SuperLU's, numpy's or CHOLMOD's words) → not held, under model.fe.fixed;
    memory, ARPACK, anything else → that cause with the model size, under reduction."""
    from scipy.sparse.linalg import ArpackNoConvergence

    from sarfe.pipeline.model.fe_stage import reduction_error

    case = load_case(yaml.load((ROOT / "cases" / "rattle_rig.yaml").read_text(), Loader=CaseLoader))
    said = {kind: str(reduction_error(case, exc, 1200, 30)) for kind, exc in {
        "superlu": RuntimeError("Factor is exactly singular"),
        "numpy": np.linalg.LinAlgError("Singular matrix"),
        "cholmod": ValueError("matrix is not positive definite"),
        "memory": MemoryError(),
        "arpack": ArpackNoConvergence("ARPACK error -1: No convergence (361 iterations)", [], []),
        "other": ValueError("boundary_dofs must be distinct positions in [0, n)")}.items()}
    for kind in ("superlu", "numpy", "cholmod"):
        assert said[kind].startswith("model.fe.fixed: the structure is not held (singular "), said
    assert said["memory"].startswith("reduction: the Craig–Bampton reduction ran out of memory "
                                     "(1200 free DOFs, 30 boundary, 1170 interior)")
    assert said["arpack"].startswith("reduction: the eigensolver of the Craig–Bampton reduction "
                                     "did not converge")
    assert said["other"] == ("reduction: the Craig–Bampton reduction failed (1200 free DOFs, 30 "
                             "boundary, 1170 interior): ValueError: boundary_dofs must be distinct "
                             "positions in [0, n)")
    assert not any("held" in said[k] for k in ("memory", "arpack", "other"))


def test_assembled_mass_of_a_rigid_translation_is_the_sum_of_rho_t_area():
    """ιᵀ M ι for a rigid translation ι (unit along x on every node) is the structure's mass
    Σ_e ρ_e t_e A_e, with each triangle's ρ and t from its element group (shell_properties)."""
    from sarfe.pipeline.model.case_mesh import load_case_mesh
    from sarfe.pipeline.model.fe_stage import assemble
    from sarfe.pipeline.model.groups import shell_properties

    case = load_case(ROOT / "cases" / "rattle_rig.yaml")
    mesh = load_case_mesh(case)
    section = shell_properties(case, mesh)
    corners = mesh.points[mesh.triangles]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0],
                                         corners[:, 2] - corners[:, 0]), axis=1)
    _, mass = assemble(case, mesh)
    iota = np.zeros(mass.shape[0])
    iota[0::6] = 1.0
    expected = float(np.sum(section.density * section.thickness * area))
    assert iota @ (mass @ iota) == pytest.approx(expected, rel=1e-12)
    assert len(set(section.density)) == 2          # plate (ABS) and beam (steel) both present


def test_erp_areas_are_the_radiating_surface_area():
    """The ERP map's nodal areas add up to the area of the radiating triangles (a third of each
    triangle to each corner)."""
    from sarfe.pipeline.model.case_mesh import load_case_mesh
    from sarfe.pipeline.model.erp_map import surface_triangles
    from sarfe.pipeline.model.linear_stage import build_linear_model

    case = load_case(ROOT / "cases" / "rattle_rig.yaml")
    stage = build_linear_model(case)
    triangles = surface_triangles(case, load_case_mesh(case))
    corners = stage.mesh.points[triangles]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0],
                                         corners[:, 2] - corners[:, 0]), axis=1).sum()
    assert stage.erp_areas.sum() == pytest.approx(area, rel=1e-12)
    assert stage.erp_map.shape == (len(stage.erp_nodes), stage.dof_count)
