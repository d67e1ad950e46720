"""Contacts of FE cases from the geometry (sarfe.pipeline.model.contact_pairs): normals from the
partner surface, points coupled by shape functions, forces on the shells' faces, surface gaps —
against the geometry the generators build."""
from pathlib import Path

import numpy as np
import pytest

from sarfe.case.errors import CaseError
from sarfe.case.read import load_case
from sarfe.erp import nodal_normals
from sarfe.mesh.generators import squeak_rig
from sarfe.pipeline.model.case_mesh import load_case_mesh
from sarfe.pipeline.model.contact_pairs import resolve_contact
from sarfe.pipeline.model.fe_stage import resolve_contacts, shell_surface

CASES = Path(__file__).resolve().parents[3] / "cases"


def rig(name, mesh_m=None, **contact):
    data = load_case(CASES / f"{name}.yaml").data
    if mesh_m is not None:
        data["model"]["fe"]["generator"]["mesh_size_m"] = mesh_m
    data["contacts"][0].update(contact)
    case = load_case(data, base_dir=CASES)
    return case, load_case_mesh(case)


def angle_deg(u, v):
    cos = np.dot(u, v) / (np.linalg.norm(u) * np.linalg.norm(v))
    return np.degrees(np.arccos(np.clip(abs(cos), 0.0, 1.0)))


def test_rattle_rig_surface_gap_normal_and_explicit_pair():
    """The striker tip's mid-surface sits 0.5 mm (generator `gap`) above the plate's: the normal
    is the plate's (−z, from a towards b), the surface gap is 0.5 mm less the half thicknesses
    (1.5 mm strip, 2.5 mm plate: −1.5 mm, an overlap the shipped case overrides with gap_m), and
    the same pair given as explicit nodes gives the same frame, gap and rows."""
    case, mesh = rig("rattle_rig")
    surface = shell_surface(case, mesh)
    tip = resolve_contact(case, mesh, 0, surface)
    n = tip.frames[0, 0]
    np.testing.assert_allclose(n, [0.0, 0.0, -1.0], atol=1e-12)
    params = case.config.model.fe.generator.params
    t = case.data["model"]["fe"]["thickness_m"]
    half = (t["part_beam"] + t["part_plate"]) / 2
    assert tip.gaps[0] == pytest.approx(params["gap"] - half, rel=1e-9)
    a, b = int(tip.nodes_a[0]), int(tip.nodes_b[0])
    assert n @ (mesh.points[b] - mesh.points[a]) == pytest.approx(params["gap"], rel=1e-9)
    # a rattle law has no tangent element: only the normal rows are kept (the boundary is what
    # moves w: here u_z of the striker and of the plate node)
    assert tip.operator[1:3].nnz == 0 and tip.operator[0].nnz == 2
    data = case.data
    data = {**data, "contacts": [{k: v for k, v in data["contacts"][0].items() if k != "between"}
                                 | {"pairs": [[a, b]]}]}
    explicit = resolve_contact(load_case(data, base_dir=CASES), mesh, 0, surface)
    np.testing.assert_allclose(explicit.frames, tip.frames, atol=1e-12)
    np.testing.assert_allclose(explicit.gaps, tip.gaps, rtol=1e-12)
    assert abs(explicit.operator - tip.operator).max() < 1e-12


def test_pairing_beyond_the_tolerance_names_the_farthest_node():
    case, mesh = rig("rattle_rig", pairing_tolerance_m=1e-4)    # the surfaces are 0.5 mm apart
    with pytest.raises(CaseError, match=r"contacts\[0\]\.between: 1 of 1 nodes of 'contact_tip_a' "
                                        r"have no point of the surface of 'contact_tip_b' within "
                                        r"pairing_tolerance_m = 0\.0001 m"):
        resolve_contacts(case, mesh)


@pytest.mark.parametrize("mesh_m", [0.012, 0.010, 0.009])
def test_squeak_rig_normal_is_the_plates_where_the_node_normal_leans(mesh_m):
    """At the pad's pole the old `auto` normal (area-weighted node normal) leans 2.4 / 4.2 /
    2.5° at 12 / 10 / 9 mm (issue 29: the sliding leaked into the plate by the tilt², 13 dB
    between meshes); the partner surface's (the flat plate's) normal is exact on every mesh,
    and the friction rows carry the face offset: a tangential slide of the plate's face moves
    its rotations by t/2 = 1.25 mm."""
    case, mesh = rig("squeak_rig", mesh_m)
    rub = resolve_contacts(case, mesh)["rub"]
    pole = mesh.node_groups["contact_rub_a"][0]
    lean = angle_deg(nodal_normals(mesh.points, mesh.triangles)[pole], [0, 0, 1])
    assert lean > 1.0                                   # the artefact the old normal carried
    np.testing.assert_allclose(rub.frames[0, 0], [0.0, 0.0, -1.0], atol=1e-12)
    assert not rub.warnings
    G = rub.operator.toarray()
    b = int(rub.nodes_b[0])                            # the plate node under the pole
    plate_rot = G[1:3, 6 * b + 3: 6 * b + 5]           # tangent rows on the plate's θx, θy
    assert np.abs(plate_rot).max() == pytest.approx(2.5e-3 / 2, rel=1e-9)


def test_points_m_couple_by_shape_functions_wherever_the_nodes_are():
    """A contact point given by coordinates (`points_m` on the plate, `surfaces`: plate → pad)
    stays where it is given on every mesh, though it lies on no node: its rows on the plate side
    are the shape functions of the triangle holding it (Σ L_i x_i = x, a partition of unity in
    the normal row), and `auto` takes the pad's fitted normal at the partner point — within
    0.2° of the sphere's (radius 12 mm, centre 12 mm above the pole) on each mesh."""
    x = np.array([0.0013, -0.0007, 0.0])                # plate mid-surface, off-node
    centre = np.array([0.0, 0.0, 0.012])
    for mesh_m in (0.012, 0.009, 0.007):
        data = load_case(CASES / "squeak_rig.yaml").data
        data["model"]["fe"]["generator"]["mesh_size_m"] = mesh_m
        contact = {k: v for k, v in data["contacts"][0].items() if k != "between"}
        data["contacts"] = [contact | {"points_m": [x.tolist()],
                                       "surfaces": ["part_plate", "part_bump"]}]
        case = load_case(data, base_dir=CASES)
        mesh = load_case_mesh(case)
        rub = resolve_contacts(case, mesh)["rub"]
        np.testing.assert_allclose(rub.points[0], x, atol=1e-12)
        assert np.linalg.norm(mesh.points - x, axis=1).min() > 1e-4      # no node there
        n = rub.frames[0, 0]
        assert n[2] > 0.99                                               # plate → pad: up
        assert angle_deg(n, centre - rub.partner_points[0]) < 0.2
        G = rub.operator.toarray()
        plate = np.unique(mesh.triangles[mesh.element_groups["part_plate"]])
        t1 = rub.frames[0, 1]
        k = int(np.argmax(np.abs(t1[:2])))                # q₁ = t₁·(u_a − u_b): membrane, linear
        L = G[1, 6 * plate + k] / t1[k]
        assert L.sum() == pytest.approx(1.0, rel=1e-9) and np.count_nonzero(L) == 3
        np.testing.assert_allclose(L @ mesh.points[plate], x, atol=1e-12)


def test_a_contact_on_a_rib_junction_is_warned_about_and_a_flat_spot_is_not():
    """`auto` on a point where a rib meets the carrier skin (a T-junction: no surface has one
    normal there) gives a one-line warning naming the contact; in the middle of the flat skin,
    none. (A grounded pair: the normal is side a's own surface's.)"""
    data = load_case(CASES / "door_trim.yaml").data
    data["model"]["fe"]["generator"]["mesh_size_m"] = 0.03
    case = load_case(data, base_dir=CASES)
    mesh = load_case_mesh(case)
    t = mesh.triangles
    rib = np.unique(t[mesh.element_groups["part_ribs"]])
    carrier = np.unique(t[mesh.element_groups["part_carrier"]])
    junction = int(np.intersect1d(rib, carrier)[len(np.intersect1d(rib, carrier)) // 2])
    flat = carrier[~np.isin(carrier, rib)]
    far = np.linalg.norm(mesh.points[flat][:, None] - mesh.points[rib][None], axis=2).min(axis=1)
    flat = int(flat[np.argmax(far)])
    contact = {k: v for k, v in data["contacts"][0].items() if k != "between"}
    data["contacts"] = [contact | {"name": "on_rib", "pairs": [[junction, "ground"]]},
                        contact | {"name": "on_skin", "pairs": [[flat, "ground"]]}]
    case = load_case(data, base_dir=CASES)
    resolved = resolve_contacts(case, mesh)
    (warning,) = resolved["on_rib"].warnings
    assert warning.startswith("contacts[0] (on_rib): the surface under 1 of 1 point(s) is folded")
    assert "give normal: [x, y, z]" in warning
    assert resolved["on_skin"].warnings == ()


def test_a_rattle_variant_of_a_squeak_contact_is_another_linear_stage():
    """A rattle keeps only the normal rows (and their boundary), so a cached squeak stage must
    not serve it, nor the reverse: the law's use of tangent rows is in the stage key."""
    from sarfe.pipeline.model.stage import linear_model_key

    case, _ = rig("squeak_rig")
    data = case.data
    rattle = {k: v for k, v in data["contacts"][0].items()
              if k not in ("tangential_stiffness_N_m", "friction_coefficient")} | {"type": "rattle"}
    other = load_case({**data, "contacts": [rattle]}, base_dir=CASES)
    assert linear_model_key(other) != linear_model_key(case)
    assert linear_model_key(load_case(data, base_dir=CASES)) == linear_model_key(case)
