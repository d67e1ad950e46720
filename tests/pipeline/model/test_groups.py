"""Node and element groups (sarfe.pipeline.model.groups): the per-triangle section of
``materials`` / ``thickness_m`` (later keys override earlier ones, '*' for every triangle) and the
one-line errors naming the key and the groups the mesh has."""
from pathlib import Path

import numpy as np
import pytest

from sarfe.case.errors import CaseError
from sarfe.case.read import load_case
from sarfe.pipeline.model.case_mesh import load_case_mesh
from sarfe.pipeline.model.groups import fixed_nodes, resolve_node_group, shell_properties

CASES = Path(__file__).resolve().parents[3] / "cases"
ABS = {"E_Pa": 2.2e9, "nu": 0.37, "rho_kg_m3": 1050.0}
STEEL = {"E_Pa": 2.1e11, "nu": 0.30, "rho_kg_m3": 7850.0}


def _rig(materials, thickness):
    data = load_case(CASES / "rattle_rig.yaml").data
    data["model"]["fe"]["materials"] = materials
    data["model"]["fe"]["thickness_m"] = thickness
    case = load_case(data, base_dir=CASES)
    return case, load_case_mesh(case)


def test_later_groups_override_the_default():
    case, mesh = _rig({"*": ABS, "part_beam": STEEL}, {"*": 2.5e-3, "part_beam": 1.5e-3})
    section = shell_properties(case, mesh)
    beam = np.zeros(mesh.n_triangles, bool)
    beam[mesh.element_groups["part_beam"]] = True
    assert np.all(section.young[beam] == STEEL["E_Pa"]) and np.all(section.young[~beam] == 2.2e9)
    assert np.all(section.thickness[beam] == 1.5e-3) and np.all(section.thickness[~beam] == 2.5e-3)
    assert np.all(section.density[beam] == 7850.0) and np.all(section.poisson[~beam] == 0.37)


def test_missing_group_and_uncovered_triangles_are_one_line_errors():
    case, mesh = _rig({"part_plate": ABS, "part_bem": STEEL}, {"*": 2.5e-3})
    with pytest.raises(CaseError, match=r"model\.fe\.materials\.part_bem: element group "
                                        r"'part_bem' not in mesh \(available: .*part_beam"):
        shell_properties(case, mesh)
    case, mesh = _rig({"part_plate": ABS}, {"*": 2.5e-3})
    with pytest.raises(CaseError, match=r"model\.fe\.materials: \d+ of \d+ triangles belong to "
                                        r"no listed element group"):
        shell_properties(case, mesh)


def test_node_groups_glob_and_fixed():
    case, mesh = _rig({"*": ABS}, {"*": 2.5e-3})
    both = resolve_node_group(case, mesh, "clamp_*", ("x",))
    clamps = np.union1d(mesh.node_groups["clamp_plate"], mesh.node_groups["clamp_beam"])
    np.testing.assert_array_equal(both, clamps)
    np.testing.assert_array_equal(fixed_nodes(case, mesh), clamps)     # fixed: both clamps
    with pytest.raises(CaseError, match="node group 'clamp_x' not in mesh"):
        resolve_node_group(case, mesh, "clamp_x", ("model", "fe", "fixed", 0))
