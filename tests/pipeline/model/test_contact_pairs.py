"""Contact geometry of FE cases (sarfe.pipeline.model.contact_pairs): frames, pairing and the
geometric gap against the geometry the generators build."""
from pathlib import Path

import numpy as np
import pytest

from sarfe.case.errors import CaseError
from sarfe.case.read import load_case
from sarfe.erp import nodal_normals
from sarfe.pipeline.model.case_mesh import load_case_mesh
from sarfe.pipeline.model.contact_pairs import frame_from_normal, pair_contact

CASES = Path(__file__).resolve().parents[3] / "cases"


def test_frames_are_right_handed_orthonormal_around_the_normal():
    rng = np.random.default_rng(0)
    normals = rng.normal(size=(200, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    frames = frame_from_normal(normals)
    np.testing.assert_allclose(frames[:, 0], normals, atol=1e-15)
    np.testing.assert_allclose(frames @ np.swapaxes(frames, 1, 2), np.broadcast_to(np.eye(3), (
        200, 3, 3)), atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(frames), 1.0, atol=1e-14)


def test_rattle_rig_gap_is_the_generators_clearance():
    """The rattle rig's striker tip sits gap = 0.5 mm (generator params) above the plate: its one
    node pair has geometric gap n·(x_b − x_a) = 0.5 mm with the normal from a towards b; the same
    pair given explicitly gives the same frame and gap."""
    case = load_case(CASES / "rattle_rig.yaml")
    mesh = load_case_mesh(case)
    normals = nodal_normals(mesh.points, mesh.triangles)
    a, b, frames, gap = pair_contact(case, mesh, 0, normals)
    assert gap == pytest.approx([case.config.model.fe.generator.params["gap"]], rel=1e-9)
    assert frames[0, 0] @ (mesh.points[b[0]] - mesh.points[a[0]]) == pytest.approx(gap[0])
    data = case.data
    data = {**data, "contacts": [{k: v for k, v in data["contacts"][0].items() if k != "between"}
                                 | {"pairs": [[int(a[0]), int(b[0])]]}]}
    explicit = load_case(data, base_dir=CASES)
    a2, b2, frames2, gap2 = pair_contact(explicit, mesh, 0, normals)
    assert (a2, b2) == (a, b)
    np.testing.assert_allclose(frames2, frames)
    np.testing.assert_allclose(gap2, gap)


def test_pairing_beyond_the_tolerance_names_the_farthest_node():
    data = load_case(CASES / "rattle_rig.yaml").data
    data["contacts"][0]["pairing_tolerance_m"] = 1e-4          # the pair is 0.5 mm apart
    case = load_case(data, base_dir=CASES)
    mesh = load_case_mesh(case)
    with pytest.raises(CaseError, match=r"contacts\[0\]\.between: 1 of 1 nodes of 'contact_tip_a' "
                                        r"have no node of 'contact_tip_b' within "
                                        r"pairing_tolerance_m = 0\.0001 m"):
        pair_contact(case, mesh, 0, nodal_normals(mesh.points, mesh.triangles))
