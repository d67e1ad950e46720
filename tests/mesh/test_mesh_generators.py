"""Parametric gmsh generators at coarse sizes: topology, groups, contact pairs, determinism."""
import importlib

import numpy as np
import pytest

from sarfe.mesh import (connected_components, load_mesh, nodal_areas, node_normals,
                        orphan_nodes, triangle_areas)

# generator → (coarse mesh size [m], extra parameters, bodies: element groups forming one body,
#              required groups, geometric gap of the contact pairs [m])
CASES = {
    "rattle_rig": (0.01, {}, [["part_beam"], ["part_plate"]],
                   ["clamp_beam", "clamp_plate", "contact_tip_a", "contact_tip_b", "excite_beam",
                    "skin", "part_beam", "part_plate"], 0.5e-3),
    "squeak_rig": (0.01, {"gap": 0.2e-3}, [["part_beam", "part_bump"], ["part_plate"]],
                   ["clamp_beam", "clamp_plate", "contact_rub_a", "contact_rub_b", "excite_beam",
                    "skin", "part_beam", "part_bump", "part_plate"], 0.2e-3),
    "door_trim": (0.03, {}, [["part_carrier", "part_ribs", "part_bosses"], ["part_map_pocket"]],
                  [f"clip_{i}" for i in range(1, 11)] + [f"clip_pocket_{i}" for i in range(1, 5)]
                  + [f"contact_{s}_{e}" for s in ("lower_1", "lower_2", "lower_3", "upper_1",
                                                  "side_left", "side_right") for e in "ab"]
                  + ["excite_carrier", "excite_pocket", "skin", "part_carrier", "part_ribs",
                     "part_bosses", "part_map_pocket"], 0.5e-3),
    "instrument_panel": (0.03, {}, [["part_carrier", "part_ribs", "part_bosses"], ["part_trim_strip"]],
                         [f"clip_{i}" for i in range(1, 11)] + [f"clip_strip_{i}" for i in range(1, 5)]
                         + [f"contact_{s}_{e}" for s in ("front_1", "front_2", "rear_1", "end_left",
                                                         "end_right") for e in "ab"]
                         + ["excite_carrier", "excite_strip", "skin", "part_carrier", "part_ribs",
                            "part_bosses", "part_trim_strip"], 0.5e-3),
}
# parts made of several disjoint pieces (each welded to the carrier skin)
SCATTERED = {"part_bosses"}

_CACHE = {}


def generated(name):
    if name not in _CACHE:
        size, params, *_ = CASES[name]
        module = importlib.import_module(f"sarfe.mesh.generators.{name}")
        _CACHE[name] = module.generate(mesh_size=size, **params)
    return _CACHE[name]


@pytest.mark.parametrize("name", list(CASES))
def test_topology_and_groups(name):
    mesh = generated(name)
    _, _, bodies, required, _ = CASES[name]
    assert len(orphan_nodes(mesh.n_nodes, mesh.triangles)) == 0
    for group in required:
        assert group in mesh.node_groups or group in mesh.element_groups, group
        size = len(mesh.node_groups.get(group, mesh.element_groups.get(group, [])))
        assert size > 0, group
    # every triangle in exactly one part; each body is one connected component
    parts = [g for g in mesh.element_groups if g.startswith("part_")]
    owner = np.concatenate([mesh.element_groups[g] for g in parts])
    assert np.array_equal(np.sort(owner), np.arange(mesh.n_triangles))
    count, labels = connected_components(mesh.n_nodes, mesh.triangles)
    assert count == len(bodies)
    for body in bodies:
        tris = mesh.triangles[np.concatenate([mesh.element_group(g) for g in body])]
        assert len(np.unique(labels[tris])) == 1, body
        for group in set(body) - SCATTERED:  # each part is itself connected
            sub = mesh.part(group)
            assert connected_components(sub.n_nodes, sub.triangles)[0] == 1, group
    # supports and excitation points are nodes of the mesh
    for group in mesh.group_names("clip_") + mesh.group_names("clamp_") + mesh.group_names("excite_"):
        assert len(mesh.node_group(group)) > 0


@pytest.mark.parametrize("name", list(CASES))
def test_contact_pairs(name):
    mesh = generated(name)
    gap = CASES[name][4]
    pairs = mesh.contact_pairs()
    assert pairs
    # contact a/b nodes lie on different bodies
    _, labels = connected_components(mesh.n_nodes, mesh.triangles)
    for pair, (a, b) in pairs.items():
        assert len(a) == len(b) == 1, pair
        distance = np.linalg.norm(mesh.points[a] - mesh.points[b], axis=1)
        assert distance == pytest.approx(gap, rel=1e-9, abs=1e-12), pair
        assert labels[a[0]] != labels[b[0]], pair
        # node normals at both ends parallel to the pair direction (b: the flat or smooth
        # partner, strict; a: a coarse mesh of a bulged part may tilt its node normal)
        d = (mesh.points[b] - mesh.points[a])[0]
        for node, limit in ((b[0], 0.995), (a[0], 0.9)):
            body = labels[mesh.triangles[:, 0]] == labels[node]
            n = node_normals(mesh.points, mesh.triangles[body & _touching(mesh, node)])[node]
            assert abs(n @ d) / np.linalg.norm(d) > limit, pair


def _touching(mesh, node):
    return np.any(mesh.triangles == node, axis=1)


@pytest.mark.parametrize("name", list(CASES))
def test_normals_unit_and_areas(name):
    mesh = generated(name)
    skin = mesh.triangles[mesh.element_group("skin")]
    normals = node_normals(mesh.points, skin)
    used = np.unique(skin)
    assert np.allclose(np.linalg.norm(normals[used], axis=1), 1.0)
    assert nodal_areas(mesh.points, skin).sum() == pytest.approx(triangle_areas(mesh.points, skin).sum(),
                                                                  rel=1e-12)


def test_rattle_plate_area_exact():
    mesh = generated("rattle_rig")
    plate = mesh.triangles[mesh.element_group("part_plate")]
    assert nodal_areas(mesh.points, plate).sum() == pytest.approx(0.15 ** 2, rel=1e-12)
    assert np.allclose(node_normals(mesh.points, plate)[np.unique(plate)], [0, 0, 1])


@pytest.mark.parametrize("name", ["rattle_rig", "squeak_rig", "door_trim"])
def test_determinism_and_msh_round_trip(name, tmp_path):
    size, params, *_ = CASES[name]
    module = importlib.import_module(f"sarfe.mesh.generators.{name}")
    first = generated(name)
    second = module.generate(mesh_size=size, path=tmp_path / "a.msh", **params)
    assert first.points.tobytes() == second.points.tobytes()
    assert np.array_equal(first.triangles, second.triangles)
    loaded = load_mesh(tmp_path / "a.msh")
    assert loaded.points.tobytes() == first.points.tobytes()
    assert np.array_equal(loaded.triangles, first.triangles)
    for group, idx in first.node_groups.items():
        assert np.array_equal(loaded.node_group(group), idx), group
    for group, idx in first.element_groups.items():
        assert np.array_equal(loaded.element_group(group), idx), group


def test_squeak_pad_touches_plate_by_default():
    from sarfe.mesh.generators import squeak_rig

    mesh = squeak_rig.generate(mesh_size=0.01)
    (a,), (b,) = mesh.contact_pairs()["rub"]
    assert np.array_equal(mesh.points[a], mesh.points[b]) and a != b
    _, labels = connected_components(mesh.n_nodes, mesh.triangles)
    assert labels[a] != labels[b]


def test_cached_mesh_equals_generated(tmp_path):
    from sarfe.mesh.cache import cached_mesh

    fresh = cached_mesh("rattle_rig", 0.01, cache_dir=tmp_path, gap=1e-3)
    files = list(tmp_path.glob("rattle_rig-*.msh"))
    assert len(files) == 1
    again = cached_mesh("rattle_rig", 0.01, cache_dir=tmp_path, gap=1e-3)
    assert again.points.tobytes() == fresh.points.tobytes()
    assert np.array_equal(again.triangles, fresh.triangles)
    assert again.node_groups.keys() == fresh.node_groups.keys()
    cached_mesh("rattle_rig", 0.01, cache_dir=tmp_path, gap=2e-3)
    assert len(list(tmp_path.glob("rattle_rig-*.msh"))) == 2


def test_mm_scaling_of_generated_file(tmp_path):
    from sarfe.mesh.generators import rattle_rig

    mesh = rattle_rig.generate(mesh_size=0.02, path=tmp_path / "rig.msh")
    scaled = load_mesh(tmp_path / "rig.msh", length_unit="mm")
    assert np.allclose(scaled.points, mesh.points * 1e-3, rtol=1e-15, atol=0)


@pytest.mark.parametrize("name", ["rattle_rig", "squeak_rig"])
def test_shipped_rig_meshes_are_current(name):
    """meshes/<rig>.msh must equal a fresh generation (rerun meshes/generate.py if not)."""
    import pathlib

    module = importlib.import_module(f"sarfe.mesh.generators.{name}")
    shipped = load_mesh(pathlib.Path(__file__).resolve().parents[2] / "meshes" / f"{name}.msh")
    fresh = module.generate(mesh_size=0.005)
    assert shipped.points.tobytes() == fresh.points.tobytes()
    assert np.array_equal(shipped.triangles, fresh.triangles)
    assert sorted(shipped.node_groups) == sorted(fresh.node_groups)


@pytest.mark.parametrize("name,attached,rib_height", [("door_trim", "part_map_pocket", 0.015),
                                                      ("instrument_panel", "part_trim_strip", 0.02)])
def test_panel_layers(name, attached, rib_height):
    """Ribs and bosses lie behind the skin, the attached part in front of it, ribs vertical."""
    mesh = generated(name)
    f = importlib.import_module(f"sarfe.mesh.generators.{name}").spec().height
    p, t = mesh.points, mesh.triangles

    def offset(group):
        nodes = np.unique(t[mesh.element_group(group)])
        return p[nodes, 2] - f(p[nodes, 0], p[nodes, 1])

    skin_error = np.abs(offset("part_carrier")).max()
    assert skin_error < 1e-3  # B-spline skin follows f(x, y)
    ribs = offset("part_ribs")
    assert ribs.min() == pytest.approx(-rib_height, abs=1e-6) and ribs.max() < skin_error
    assert offset("part_bosses").max() < skin_error
    assert offset(attached).min() > 0  # never behind the carrier skin
    rib_normals = node_normals(p, t[mesh.element_group("part_ribs")])
    used = np.unique(t[mesh.element_group("part_ribs")])
    assert np.abs(rib_normals[used, 2]).max() < 1e-6


def test_contact_frames():
    from sarfe.mesh import contact_frames

    normal, tangents, gap = contact_frames(generated("rattle_rig"))["tip"]
    assert np.allclose(normal, [[0, 0, -1]]) and gap == pytest.approx([0.5e-3], rel=1e-12)
    frame = np.concatenate([tangents[0], normal], axis=0)  # rows t1, t2, n
    assert np.allclose(frame @ frame.T, np.eye(3)) and np.linalg.det(frame) == pytest.approx(1.0)
    from sarfe.mesh.generators import squeak_rig

    normal, _, gap = contact_frames(squeak_rig.generate(mesh_size=0.01))["rub"]
    assert gap[0] == 0.0 and np.allclose(normal, [[0, 0, -1]])  # from the pad down into the plate
    for pair, (normal, _, gap) in contact_frames(generated("door_trim")).items():
        assert gap == pytest.approx(0.5e-3, rel=1e-9) and normal[0, 2] < -0.9, pair


def test_door_trim_contact_spot_counts():
    """rattle_spots / squeak_spots add named spot pairs on the pocket flange (18 at most), each a
    node pair 0.5 mm apart along the skin normal; the default counts give the demo's six spots."""
    from sarfe.mesh import contact_frames
    from sarfe.mesh.generators import door_trim

    assert list(door_trim.contact_spots()) == ["lower_1", "lower_2", "lower_3", "upper_1",
                                               "side_left", "side_right"]
    mesh = door_trim.generate(mesh_size=0.03, rattle_spots=12, squeak_spots=6)
    frames = contact_frames(mesh)
    assert len(frames) == 18
    assert set(frames) == set(door_trim.contact_spots(12, 6))
    for pair, (normal, _, gap) in frames.items():
        assert gap == pytest.approx(0.5e-3, rel=1e-9) and normal[0, 2] < -0.9, pair
    a = np.array([mesh.points[mesh.node_groups[f"contact_{p}_b"][0]] for p in frames])
    spacing = np.linalg.norm(a[:, None] - a[None], axis=-1) + np.eye(len(a))
    assert spacing.min() > 0.04                     # distinct spots, ≥ 40 mm apart
    default = generated("door_trim")
    assert door_trim.generate(mesh_size=0.03, rattle_spots=4, squeak_spots=2).points.tobytes() \
        == default.points.tobytes()
    for bad in ({"rattle_spots": 13}, {"squeak_spots": -1}, {"rattle_spots": 2.0},
                {"rattle_spots": 0, "squeak_spots": 0}):
        with pytest.raises(ValueError):
            door_trim.spec(**bad)
