"""The deck path of a case (model.fe.deck) on a small Abaqus plate: the deck's own sections,
supports, loads and springs are used; springs named by a contact's from_elements become the
contact; bad decks (unsupported keywords, structures not held, duplicate or zero-area elements)
are refused at validate with one line naming what is wrong."""
import numpy as np
import pytest

from sarfe.case.errors import CaseError
from sarfe.pipeline import build_linear_model, check_mesh, load_case, solve_case

NX, NY, LX, LY = 8, 4, 200.0, 100.0      # mm
E_MPA, NU, RHO, T_MM = 2000.0, 0.38, 1.0e-9, 2.5


def plate_inp(extra="", boundary="clamped, ENCASTRE\n", duplicate=False):
    """A flat S4R plate in mm-t-s, clamped along x = 0, a grounded spring (id 900, DOF 3) at
    the far corner, a point mass, and a *CLOAD step 'shake' at the far edge's middle."""
    nodes, elements = [], []
    nid = lambda i, j: 1 + i + (NX + 1) * j                       # noqa: E731
    for j in range(NY + 1):
        for i in range(NX + 1):
            nodes.append(f"{nid(i, j)}, {LX * i / NX}, {LY * j / NY}, 0.")
    for j in range(NY):
        for i in range(NX):
            elements.append(f"{1 + i + NX * j}, {nid(i, j)}, {nid(i + 1, j)}, "
                            f"{nid(i + 1, j + 1)}, {nid(i, j + 1)}")
    if duplicate:
        elements.append(f"999, {nid(1, 0)}, {nid(2, 0)}, {nid(2, 1)}, {nid(1, 1)}")
    corner, middle = nid(NX, NY), nid(NX, NY // 2)
    return "\n".join([
        "*HEADING", "sarfe test plate", "*NODE", *nodes,
        "*ELEMENT, TYPE=S4R, ELSET=plate", *elements,
        "*ELEMENT, TYPE=SPRING1, ELSET=clip", f"900, {corner}",
        "*ELEMENT, TYPE=MASS, ELSET=lump", f"901, {middle}",
        "*NSET, NSET=clamped, GENERATE", f"1, {nid(0, NY)}, {NX + 1}",
        "*NSET, NSET=corner", f"{corner}", "*NSET, NSET=ground_side", f"{nid(0, 0)}",
        "*MATERIAL, NAME=PP", "*ELASTIC", f"{E_MPA}, {NU}", "*DENSITY", f"{RHO}",
        "*SHELL SECTION, ELSET=plate, MATERIAL=PP", f"{T_MM}",
        "*SPRING, ELSET=clip", "3", "20.",                          # 20 N/mm = 2e4 N/m
        "*MASS, ELSET=lump", "0.005",                               # 0.005 t = 5 kg
        "*BOUNDARY", boundary.strip(), extra.strip(),
        "*STEP, NAME=shake", "*STATIC",
        "*CLOAD", f"{middle}, 3, 1.0", "*END STEP", ""])


def write_case(tmp_path, inp, **fe):
    (tmp_path / "plate.inp").write_text(inp)
    case = {"name": "plate", "model": {"fe": {"deck": "plate.inp", "units": "mm-t-s", **fe}},
            "excitation": {"forces": [{"load_set": "shake", "scale": 0.5}],
                           "frequency_hz": [20.0]},
            "damping": {"modal_zeta": 0.02}, "reduction": {"mode_count": 12},
            "solver": {"harmonics": 1, "samples_per_period": 16, "error_estimate": False,
                       "stability": False}}
    return case


def test_deck_properties_supports_loads_are_used(tmp_path):
    case = load_case(write_case(tmp_path, plate_inp()), base_dir=tmp_path)
    stage = build_linear_model(case)
    area = LX * LY * 1e-6
    # shell ρ t A + the 5 kg point mass (0.005 t)
    assert stage.info["total_mass_kg"] == pytest.approx(RHO * 1e12 * T_MM * 1e-3 * area + 5.0,
                                                        rel=1e-12)
    assert stage.info["radiating_area_m2"] == pytest.approx(area, rel=1e-12)
    # the clamped edge: 5 nodes x 6 DOFs held; the load set's DOF is a boundary coordinate
    assert stage.info["held_dofs"] == (NY + 1) * 6
    assert stage.load_vectors.shape == (1, stage.dof_count)
    assert np.count_nonzero(stage.load_vectors[0][:stage.info["boundary_dofs"]]) == 1
    assert stage.load_vectors[0].max() == pytest.approx(1.0)     # 1 N (scale applied later)
    result = solve_case(case, linear_stage=stage, write=False)
    assert result.summary["points"][0]["converged"]


def test_spring_becomes_contact_with_its_stiffness(tmp_path):
    """A preloaded rattle contact that never opens behaves as the spring it replaces: the same
    ERP as the linear model that keeps the spring."""
    data = write_case(tmp_path, plate_inp())
    kept = solve_case(load_case(data, base_dir=tmp_path), write=False)
    data["contacts"] = [{"name": "clip", "type": "rattle", "from_elements": [900],
                         "preload_N": 50.0}]
    case = load_case(data, base_dir=tmp_path)
    stage = build_linear_model(case)
    geometry = stage.contacts["clip"]
    assert np.array_equal(geometry.nodes_b, [-1])                  # grounded spring
    assert np.allclose(geometry.frames[0, 0], [0, 0, 1])            # its axis (DOF 3)
    assert geometry.normal_stiffness.tolist() == [pytest.approx(2e4)]
    as_contact = solve_case(case, linear_stage=stage, write=False)
    point = as_contact.summary["points"][0]
    assert point["contacts"][0]["open_fraction"] == 0.0
    assert point["erp"]["level_db"] == pytest.approx(kept.summary["points"][0]["erp"]["level_db"],
                                                     abs=0.01)
    # the linear baseline keeps a preloaded (closed) contact as its spring (issue 13 item 7): the
    # spring never opens here, so the baseline is the same linear structure as the solve
    assert as_contact.summary["points"][0]["linear"]["erp_level_db"] == pytest.approx(
        point["erp"]["level_db"], abs=0.01)


def test_unsupported_keyword_is_refused_then_ignored(tmp_path):
    inp = plate_inp().replace("*HEADING", "*SURFACE, NAME=top\nplate, SPOS\n*HEADING")
    data = write_case(tmp_path, inp)
    with pytest.raises(CaseError, match=r"model\.fe\.deck: .*1 card type sarfe does not model: "
                                        r"\*SURFACE \(1, first at .*plate\.inp:1\)"):
        check_mesh(load_case(data, base_dir=tmp_path))
    data["model"]["fe"]["ignore_cards"] = ["*SURFACE"]
    info = check_mesh(load_case(data, base_dir=tmp_path))
    assert info["ignored_cards"] == {"*SURFACE": 1}
    data["model"]["fe"]["ignore_cards"] = ["CBAR"]
    with pytest.raises(CaseError, match=r"ignore_cards\[0\]: 'CBAR' is not an unsupported card"):
        check_mesh(load_case(data, base_dir=tmp_path))


@pytest.mark.parametrize("boundary, expected", [
    # z held at one node, the spring along x at another: 4 of 6 motions left
    ("ground_side, 3\n", r"a part of 45 nodes \(GRIDs 1…45\) is free in 4 rigid-body motions "
                          r"\(translation x, translation y, translation z, rotation about x, rotation about y, "
                          r"rotation about z\)"),
    # all six held at one node: nothing free
    ("ground_side, ENCASTRE\n", None),
])
def test_structure_not_held_is_found_before_any_solve(tmp_path, boundary, expected):
    inp = plate_inp(boundary=boundary).replace("*SPRING, ELSET=clip\n3\n", "*SPRING, ELSET=clip\n1\n")
    case = load_case(write_case(tmp_path, inp), base_dir=tmp_path)
    if expected is None:
        check_mesh(case)
        return
    with pytest.raises(CaseError, match="model.fe.supports: the structure is not held after the "
                                        "supports: " + expected):
        check_mesh(case)


def test_duplicate_and_zero_area_elements_are_named(tmp_path):
    with pytest.raises(CaseError, match=r"1 duplicate shell element\(s\) on the same nodes: 999 \(= 2\)"):
        check_mesh(load_case(write_case(tmp_path, plate_inp(duplicate=True)), base_dir=tmp_path))
    inp = plate_inp().replace("*ELEMENT, TYPE=SPRING1", "*ELEMENT, TYPE=S3, ELSET=plate\n"
                              "998, 1, 2, 3\n*ELEMENT, TYPE=SPRING1")
    with pytest.raises(CaseError, match=r"1 zero-area shell element\(s\): 998"):
        check_mesh(load_case(write_case(tmp_path, inp), base_dir=tmp_path))


def test_coincident_unjoined_nodes_are_reported(tmp_path):
    inp = plate_inp().replace("*ELEMENT, TYPE=S4R", "5001, 200., 100., 0.\n*ELEMENT, TYPE=S4R")
    inp = inp.replace("*ELEMENT, TYPE=SPRING1", "*ELEMENT, TYPE=S3, ELSET=plate\n"
                      "997, 5001, 44, 35\n*ELEMENT, TYPE=SPRING1")
    info = check_mesh(load_case(write_case(tmp_path, inp), base_dir=tmp_path))
    assert info["coincident_nodes"] == [[45, 5001]]


def test_grid_id_pairs_and_missing_sets(tmp_path):
    data = write_case(tmp_path, plate_inp())
    data["contacts"] = [{"name": "tip", "type": "rattle", "pairs": [[45, "ground"]],
                         "normal_stiffness_N_m": 1e4, "gap_m": 1e-4}]
    info = check_mesh(load_case(data, base_dir=tmp_path))
    assert info["contact_pairs"] == {"tip": 1}
    data["contacts"][0]["pairs"] = [[4500, "ground"]]
    with pytest.raises(CaseError, match=r"contacts\[0\]\.pairs\[0\]\[0\]: node id 4500 is not in the deck"):
        check_mesh(load_case(data, base_dir=tmp_path))
    data["contacts"] = []
    data["model"]["fe"]["supports"] = ["initial"]
    with pytest.raises(CaseError, match=r"support set 'initial' not in the deck \(available: boundary\)"):
        check_mesh(load_case(data, base_dir=tmp_path))


def test_outputs_carry_the_deck_ids(tmp_path):
    import json

    import pyvista as pv

    data = write_case(tmp_path, plate_inp())
    data["contacts"] = [{"name": "tip", "type": "rattle", "pairs": [[45, "ground"]],
                         "normal_stiffness_N_m": 1e4, "gap_m": 1e-3}]
    data["output"] = {"files": ["summary", "erp_vtu"]}
    result = solve_case(load_case(data, base_dir=tmp_path), output_dir=tmp_path / "out")
    summary = json.loads((result.output_dir / "summary.json").read_text())
    assert summary["contacts"][0]["node_pairs"] == [[45, "ground"]]
    grid = pv.read(result.output_dir / "erp.vtu")
    assert np.array_equal(np.asarray(grid.point_data["node_id"]), np.arange(1, 46))


SHEAR_DECK = """SOL 103
CEND
BEGIN BULK
GRID,1,,0.,0.,0.
GRID,2,,100.,0.,0.
GRID,3,,100.,100.,0.
GRID,4,,0.,100.,0.
GRID,5,,200.,0.,0.
GRID,6,,200.,100.,0.
CQUAD4,1,1,1,2,3,4
CQUAD4,3,1,2,5,6,3
CSHEAR,2,2,2,5,6,3
PSHELL,1,1,2.,1
PSHEAR,2,1,3.
MAT1,1,2000.,,0.3,1.e-9
SPC1,1,123456,1,4
ENDDATA
"""


def test_ignored_cards_and_their_mass_are_recorded(tmp_path):
    """A Nastran shear panel (CSHEAR, not modelled) named in ignore_cards: the run goes on
    without it and the summary says what was left out and the mass it carried (ρ t A)."""
    (tmp_path / "shear.bdf").write_text(SHEAR_DECK)
    data = {"name": "shear", "model": {"fe": {"deck": "shear.bdf", "units": "mm-t-s"}},
            "excitation": {"base_acceleration": {"direction": "z", "amplitude_m_s2": 1.0},
                           "frequency_hz": 10.0},
            "reduction": {"mode_count": 4}, "solver": {"harmonics": 1, "samples_per_period": 8,
                                                        "error_estimate": False, "stability": False}}
    with pytest.raises(CaseError, match=r"CSHEAR \(1, first at .*shear\.bdf:\d+\), "
                                        r"PSHEAR \(1, first at .*shear\.bdf:\d+\)"):
        check_mesh(load_case(data, base_dir=tmp_path))
    data["model"]["fe"]["ignore_cards"] = ["CSHEAR", "PSHEAR"]
    result = solve_case(load_case(data, base_dir=tmp_path), write=False)
    model = result.summary["model"]
    assert model["ignored_cards"] == {"CSHEAR": 1, "PSHEAR": 1}
    assert model["ignored_mass_kg"]["CSHEAR"] == pytest.approx(1000 * 3e-3 * 0.01, rel=1e-12)
    # what stays: two 100 x 100 x 2 mm quads, ρ = 1000 kg/m³
    assert model["total_mass_kg"] == pytest.approx(1000 * 2e-3 * 2 * 0.01, rel=1e-12)


def test_deck_without_mass_is_refused_at_validate(tmp_path):
    """Patran decks often carry MAT1 without density (shared plate.bdf, a101x.dat): no mass,
    no dynamics — one line at validate instead of a solver failure."""
    data = write_case(tmp_path, plate_inp().replace(f"*DENSITY\n{RHO}\n", "")
                      .replace("*MASS, ELSET=lump\n0.005\n", "*MASS, ELSET=lump\n0.\n"))
    with pytest.raises(CaseError, match=r"model\.fe\.deck: the deck has no mass"):
        check_mesh(load_case(data, base_dir=tmp_path))


def test_validate_cli_lists_ignored_cards_and_errors_in_one_line(tmp_path, capsys):
    import yaml

    from sarfe import cli

    inp = plate_inp().replace("*HEADING", "*SURFACE, NAME=top\nplate, SPOS\n*HEADING")
    data = write_case(tmp_path, inp)
    path = tmp_path / "case.yaml"
    path.write_text(yaml.safe_dump(data))
    assert cli.main(["validate", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "*SURFACE (1, first at " in err and "ignore_cards" in err
    data["model"]["fe"]["ignore_cards"] = ["*SURFACE"]
    path.write_text(yaml.safe_dump(data))
    assert cli.main(["validate", str(path)]) == 0
    assert "ignored cards: *SURFACE (1)" in capsys.readouterr().out


def test_linear_stage_key_follows_included_files(tmp_path):
    from sarfe.pipeline import linear_model_key

    (tmp_path / "nodes.inc").write_text(plate_inp().split("*ELEMENT")[0].replace("*HEADING\nsarfe test plate\n", ""))
    body = "*ELEMENT" + plate_inp().split("*ELEMENT", 1)[1]
    data = write_case(tmp_path, "*INCLUDE, INPUT=nodes.inc\n" + body)
    key = linear_model_key(load_case(data, base_dir=tmp_path))
    text = (tmp_path / "nodes.inc").read_text().replace("200.0, 100.0, 0.", "200.0, 101.0, 0.")
    (tmp_path / "nodes.inc").write_text(text)
    assert linear_model_key(load_case(data, base_dir=tmp_path)) != key


def test_yaml_overrides_a_group_section(tmp_path):
    """The deck's own sections by default; a case may override a group's thickness (material
    kept, A ∝ t, D ∝ t³, mass ∝ t) or its material."""
    from sarfe.pipeline.model.deck_model import apply_overrides, deck_panel_mesh, read_case_deck

    data = write_case(tmp_path, plate_inp(), thickness_m={"plate": 5e-3})
    case = load_case(data, base_dir=tmp_path)
    deck = read_case_deck(case)
    changed = apply_overrides(case, deck, deck_panel_mesh(case, deck))
    assert np.allclose(changed.shells.membrane, 2 * deck.shells.membrane, rtol=1e-12)
    assert np.allclose(changed.shells.bending, 8 * deck.shells.bending, rtol=1e-12)
    assert np.allclose(changed.shells.mass_per_area, 2 * deck.shells.mass_per_area, rtol=1e-12)
    data = write_case(tmp_path, plate_inp(),
                      materials={"*": {"E_Pa": 2.2e9, "nu": 0.35, "rho_kg_m3": 1050.0}})
    stage = build_linear_model(load_case(data, base_dir=tmp_path))
    assert stage.info["total_mass_kg"] == pytest.approx(1050.0 * T_MM * 1e-3 * 0.02 + 5.0, rel=1e-12)
    data = write_case(tmp_path, plate_inp(), thickness_m={"nowhere": 1e-3})
    with pytest.raises(CaseError, match=r"model\.fe\.thickness_m\.nowhere: element group 'nowhere' not in the deck"):
        check_mesh(load_case(data, base_dir=tmp_path))


DAMPER_DECK = SHEAR_DECK.replace("CSHEAR,2,2,2,5,6,3\n", "CBUSH,7,9,6,,,,,0\n").replace(
    "PSHEAR,2,1,3.\n", "PBUSH,9,K,0.,0.,5.,0.,0.,0.\n,,B,0.,0.,{b},0.,0.,0.\n")


def test_bush_dampers_enter_the_reduced_damping(tmp_path):
    """A grounded CBUSH with B3 = 0.04 N s/mm (40 N s/m) at GRID 6: its reduced damping on the
    boundary DOF uz(6) is exactly 40 N s/m; the response at resonance drops when B grows."""
    levels = []
    for b in (0.0, 0.04):
        (tmp_path / "damper.bdf").write_text(DAMPER_DECK.format(b=b))
        data = {"name": "damper", "model": {"fe": {"deck": "damper.bdf", "units": "mm-t-s",
                                                   "node_groups": {"tip": [6]}}},
                "excitation": {"forces": [{"group": "tip", "direction": "z", "force_N": 1.0}],
                               "frequency_hz": 10.0},
                "damping": {"modal_zeta": 0.01}, "reduction": {"mode_count": 4},
                "solver": {"harmonics": 1, "samples_per_period": 8, "error_estimate": False,
                           "stability": False}}
        case = load_case(data, base_dir=tmp_path)
        stage = build_linear_model(case)
        if b == 0.0:
            assert stage.added_damping is None
            # tune to the first system mode (boundary free) for the second run
            from scipy.linalg import eigh
            first = np.sqrt(eigh(stage.stiffness, stage.mass, eigvals_only=True)[0]) / (2 * np.pi)
            data["excitation"]["frequency_hz"] = float(first)
        else:
            z = np.flatnonzero(stage.load_vectors[0])[0]         # the boundary DOF uz(6)
            assert stage.added_damping[z, z] == pytest.approx(40.0, rel=1e-12)
            assert np.count_nonzero(np.abs(stage.added_damping) > 1e-12) == 1
        levels.append(solve_case(load_case(data, base_dir=tmp_path), write=False)
                      .summary["points"][0]["erp"]["level_db"])
    assert levels[1] < levels[0] - 1.0


BUSH_DECK = SHEAR_DECK.replace("CSHEAR,2,2,2,5,6,3\n", "GRID,7,,200.,100.,0.\nCBUSH,7,9,6,7,,,,0\n").replace(
    "PSHEAR,2,1,3.\n", "PBUSH,9,K,{k}\n").replace("SPC1,1,123456,1,4\n", "SPC1,1,123456,1,4,7\n")


@pytest.mark.parametrize("k, axis, expected", [
    ("1.,2.,5.,0.,0.,0.", None, ([0, 0, 1], 5e3, 1.5e3)),      # largest stiffness: axis 3
    ("5.,5.,1.,0.,0.,0.", 1, ([1, 0, 0], 5e3, 3e3)),            # a tie needs element_axis
    ("5.,5.,1.,0.,0.,0.", None, "equally stiff along two axes; give element_axis"),
])
def test_cbush_squeak_contact_takes_axis_and_stiffness_from_the_element(tmp_path, k, axis, expected):
    from sarfe.pipeline.model.deck_model import read_case_deck, springs_to_contacts

    (tmp_path / "bush.bdf").write_text(BUSH_DECK.format(k=k))
    contact = {"name": "clip", "type": "squeak", "from_elements": [7], "friction_coefficient": 0.3,
               "preload_N": 1.0}
    if axis:
        contact["element_axis"] = axis
    data = {"name": "bush", "model": {"fe": {"deck": "bush.bdf", "units": "mm-t-s"}},
            "contacts": [contact], "excitation": {"base_acceleration": {"direction": "z",
                                                                        "amplitude_m_s2": 1.0},
                                                  "frequency_hz": 10.0}}
    case = load_case(data, base_dir=tmp_path)
    if isinstance(expected, str):
        with pytest.raises(CaseError, match=r"contacts\[0\]\.from_elements: element 7 is " + expected):
            springs_to_contacts(case, read_case_deck(case))
        return
    deck, contacts, warnings = springs_to_contacts(case, read_case_deck(case))
    assert warnings == []                                        # squeak keeps k_t
    assert len(deck.springs.element_ids) == 0                    # left the linear model
    normal, k_n, k_t = expected
    assert np.allclose(contacts["clip"].frames[0, 0], normal)
    assert contacts["clip"].normal_stiffness.tolist() == [pytest.approx(k_n)]
    assert contacts["clip"].tangential_stiffness.tolist() == [pytest.approx(k_t)]


def test_abaqus_beam_stiffener_is_read_into_the_case(tmp_path):
    """A B31 rib (*BEAM SECTION RECT 4 × 6 mm) along the free edge y = LY of the plate: the
    case's mass gains ρ A L exactly and the rib stiffens the plate (first mode up)."""
    nid = lambda i: 1 + i + (NX + 1) * NY                           # noqa: E731
    rib = "\n".join(["*ELEMENT, TYPE=B31, ELSET=rib",
                     *[f"{700 + i}, {nid(i)}, {nid(i + 1)}" for i in range(NX)],
                     "*BEAM SECTION, ELSET=rib, MATERIAL=PP, SECTION=RECT", "4., 6.", "0., 0., 1."])
    plain = build_linear_model(load_case(write_case(tmp_path, plate_inp()), base_dir=tmp_path))
    ribbed = build_linear_model(load_case(write_case(tmp_path, plate_inp(extra=rib)),
                                          base_dir=tmp_path))
    added = RHO * 1e12 * (4.0 * 6.0 * 1e-6) * (LX * 1e-3)
    assert ribbed.info["total_mass_kg"] - plain.info["total_mass_kg"] == pytest.approx(added,
                                                                                      rel=1e-9)
    assert ribbed.mode_frequencies_hz[0] > plain.mode_frequencies_hz[0]
