"""`sarfe validate` catches everything `sarfe solve` rejects on input (issue 32, item 7).

Broken copies of every shipped case (cases/*.yaml), one mistake each — wrong keys, ranges and
types, cross-key rules, unknown groups and sets, a ``fixed`` that holds every node (``["*"]``),
a force or a contact on held nodes only, contacts that join a group with itself or
list a node pair twice, matrices and DOFs out of shape, deck sets and cards that are not there, an
output folder holding an input. For each, `sarfe validate` and `sarfe solve` must give the same
one line on stderr (naming the file and the key) and the same exit code 2, with no output folder
written: solve stops at the same check as validate, before any work.
"""
from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from sarfe.case.read import CaseLoader
from sarfe.cli import main

ROOT = Path(__file__).resolve().parents[2]
CASES = ROOT / "cases"


def shipped(name: str) -> dict:
    """cases/<name>.yaml as a mapping, with its file names made absolute (the copy lives
    elsewhere)."""
    data = yaml.load((CASES / f"{name}.yaml").read_text(), Loader=CaseLoader)
    fe = data["model"].get("fe", {})
    if "deck" in fe:
        fe["deck"] = str((CASES / fe["deck"]).resolve())
    return data


def at(data, path):
    for key in path:
        data = data.setdefault(key, {}) if isinstance(data, dict) else data[key]
    return data


def put(path, value):
    def change(data):
        at(data, path[:-1])[path[-1]] = value
    return change


def drop(path):
    def change(data):
        del at(data, path[:-1])[path[-1]]
    return change


def both(*changes):
    def change(data):
        for one in changes:
            one(data)
    return change


# (id, shipped case, change, fragments of the one error line)
MUTATIONS = [
    # door_trim (generator, six contacts, base excitation)
    ("door-unknown-law", "door_trim", put(("contacts", 0, "type"), "clatter"),
     ["contacts[0].type", "clatter"]),
    ("door-E-in-MPa", "door_trim", lambda d: next(iter(
        d["model"]["fe"]["materials"].values())).update(E_Pa=2200.0), ["E_Pa", "pascals"]),
    ("door-unknown-group", "door_trim", put(("contacts", 2, "between", 1), "contact_none"),
     ["contacts[2].between[1]", "contact_none"]),
    ("door-self-contact", "door_trim", lambda d: d["contacts"][3].update(
        between=[d["contacts"][3]["between"][0]] * 2), ["contacts[3].between[1]", "both sides"]),
    ("door-output-file-kind", "door_trim", put(("output", "files"), ["summary", "movie"]),
     ["output.files[1]", "movie"]),
    # door_trim_p1 (the fine mesh: only checks before the mesh)
    ("p1-harmonics-zero", "door_trim_p1", put(("solver", "harmonics"), 0),
     ["solver.harmonics", ">= 1"]),
    ("p1-samples-too-few", "door_trim_p1", both(put(("solver", "harmonics"), 8),
                                                 put(("solver", "samples_per_period"), 9)),
     ["solver.samples_per_period", "2H+1 = 17"]),
    # instrument_panel
    ("panel-both-cutoff-and-count", "instrument_panel",
     lambda d: d.setdefault("reduction", {}).update(mode_count=20, cutoff_hz=500.0),
     ["reduction", "give only one of"]),
    ("panel-missing-fixed-group", "instrument_panel", put(("model", "fe", "fixed"), ["clip_99"]),
     ["model.fe.fixed[0]", "clip_99"]),
    ("panel-nu-half", "instrument_panel", lambda d: next(iter(
        d["model"]["fe"]["materials"].values())).update(nu=0.5), ["nu", "0.5"]),
    ("panel-zeta-modes-reversed", "instrument_panel",
     put(("damping", "modal_zeta"), [{"modes": [5, 2], "zeta": 0.02}]),
     ["damping.modal_zeta[0].modes", "first <= last"]),
    # instrument_panel_sweep (a sweep with output.maps)
    ("panel-sweep-maps-every-zero", "instrument_panel_sweep",
     put(("output", "maps"), {"every": 0}), ["output.maps.every", ">= 1"]),
    # squeak_rig (friction)
    ("squeak-no-friction", "squeak_rig", drop(("contacts", 0, "friction_coefficient")),
     ["contacts[0].friction_coefficient", "missing required key"]),
    ("squeak-self-contact", "squeak_rig",
     put(("contacts", 0, "between"), ["contact_rub_a", "contact_rub_a"]), ["both sides"]),
    ("squeak-generator-param", "squeak_rig",
     put(("model", "fe", "generator", "params"), {"pad_radius_mm": 5}),
     ["model.fe.generator.params.pad_radius_mm"]),
    ("squeak-zero-direction", "squeak_rig", put(("excitation", "forces", 0, "direction"),
                                                [0, 0, 0]),
     ["excitation.forces[0].direction", "non-zero"]),
    # rattle_rig
    ("rig-unknown-surface", "rattle_rig", put(("erp", "surface"), "roof"), ["erp.surface", "roof"]),
    ("rig-surface-without-triangles", "rattle_rig", put(("erp", "surface"), "clamp_plate"),
     ["erp.surface", "node group 'clamp_plate' contains no whole triangle"]),   # was solve-only
    ("rig-pairing-tolerance", "rattle_rig", put(("contacts", 0, "pairing_tolerance_m"), 1e-6),
     ["contacts[0]"]),
    ("rig-thickness-mm", "rattle_rig", put(("model", "fe", "thickness_m", "part_plate"), 2.5),
     ["thickness_m.part_plate", "given in mm"]),
    ("rig-E-negative", "rattle_rig", lambda d: d["model"]["fe"]["materials"]["part_plate"].update(
        E_Pa=-2.2e9), ["materials.part_plate.E_Pa", "must be > 0"]),
    ("rig-fixed-everything", "rattle_rig", put(("model", "fe", "fixed"), ["*"]),
     ["model.fe.fixed", "every node of the model is held (", "'*' matches every group"]),
    ("rig-contact-held", "rattle_rig", put(("model", "fe", "fixed"),
                                           ["clamp_*", "contact_tip_a", "contact_tip_b"]),
     ["contacts[0]", "held on both sides", "the contact can never move"]),
    # rattle_rig_deck (the deck path)
    ("deck-fixed-everything", "rattle_rig_deck", put(("model", "fe", "fixed"), ["*"]),
     ["model.fe.fixed", "every node of the model is held ("]),        # was: solve "not held"
    ("deck-contact-held", "rattle_rig_deck", put(("model", "fe", "fixed"), ["set_101", "set_102"]),
     ["contacts[0]", "node pair 9–10", "held on both sides"]),        # was: solved as silence
    ("deck-force-held", "rattle_rig_deck", put(("model", "fe", "fixed"), ["set_103"]),
     ["excitation.forces[0].group", "acts on no free DOF"]),           # was: solved as silence
    ("deck-missing-support-set", "rattle_rig_deck", put(("model", "fe", "supports"), [99]),
     ["model.fe.supports"]),
    ("deck-ignored-card-absent", "rattle_rig_deck",
     put(("model", "fe", "ignore_cards"), ["CBAR"]), ["model.fe.ignore_cards[0]", "CBAR"]),
    ("deck-missing-load-set", "rattle_rig_deck", put(("excitation", "forces", 0),
                                                     {"load_set": 77}),
     ["excitation.forces[0].load_set", "77"]),
    ("deck-missing-contact-set", "rattle_rig_deck",
     put(("contacts", 0, "between", 1), "set_999"), ["contacts[0].between[1]", "999"]),
    ("deck-missing-surface", "rattle_rig_deck", put(("erp", "surface"), "pid_99"),
     ["erp.surface", "pid_99"]),
    ("deck-pair-twice", "rattle_rig_deck", lambda d: d["contacts"][0].pop("between") and
        d["contacts"][0].update(pairs=[[9, 10], [9, 10]]),
     ["contacts[0]", "is listed twice in this contact"]),
    ("deck-mesh-units-key", "rattle_rig_deck", put(("model", "fe", "mesh_units"), "mm"),
     ["model.fe.mesh_units", "with model.fe.deck"]),
    # lumped_rattle (matrices)
    ("lumped-tangent-twice", "lumped_rattle", put(("contacts", 1, "tangential_dofs"), [2, 2]),
     ["contacts[1].tangential_dofs[1]", "already contacts[1].tangential_dofs[0]"]),
    ("lumped-dof-relative-to-itself", "lumped_rattle",
     put(("contacts", 0, "normal_dof"), {"dof": 1, "relative_to": 1}),
     ["contacts[0].normal_dof.relative_to", "relative to itself"]),
    ("lumped-normal-is-tangent", "lumped_rattle",
     lambda d: d["contacts"][1].update(normal_dof=2, normal_stiffness_N_m=1e6),
     ["contacts[1].tangential_dofs[0]", "is already contacts[1].normal_dof"]),
    ("lumped-areas-count", "lumped_rattle", put(("erp", "areas_m2"), [0.06, 0.02]),
     ["erp.areas_m2", "one area per DOF"]),
    ("lumped-stiffness-shape", "lumped_rattle",
     put(("model", "matrices", "stiffness"), [[2.0e4, 0.0], [0.0, 2.0e5]]),
     ["model.matrices"]),
    ("lumped-dof-out-of-range", "lumped_rattle", put(("contacts", 1, "tangential_dofs"), [7]),
     ["contacts[1].tangential_dofs[0]", "out of range"]),
    ("lumped-influence-length", "lumped_rattle",
     put(("excitation", "base_acceleration", "influence"), [1.0, 0.2]),
     ["excitation.base_acceleration.influence"]),
    ("lumped-erp-dof-out-of-range", "lumped_rattle", put(("erp", "dofs"), [5]),
     ["erp.dofs"]),
    ("lumped-negative-tolerance", "lumped_rattle", put(("contacts", 0, "tolerance_m"), -1e-5),
     ["contacts[0].tolerance_m"]),
    ("lumped-curve-file-missing", "lumped_rattle", lambda d: d["contacts"].__setitem__(
        0, {"name": "pad", "type": "tabulated", "normal_dof": {"dof": 0, "relative_to": 1},
            "gap_m": 1e-4, "curve_file": "/nowhere/pad.csv"}),
     ["contacts[0].curve_file", "not found"]),
    ("lumped-force-dof-out-of-range", "lumped_rattle", lambda d: d["excitation"].update(
        forces=[{"dof": 9, "force_N": 1.0}], base_acceleration=None) or
        d["excitation"].pop("base_acceleration"), ["excitation.forces[0].dof"]),
]


def test_every_shipped_case_is_mutated():
    names = {path.stem for path in CASES.glob("*.yaml")}
    assert names <= {case for _, case, _, _ in MUTATIONS}, names
    assert len(MUTATIONS) >= 30 and len({m[0] for m in MUTATIONS}) == len(MUTATIONS)


def run(capsys, command, case, output):
    code = main([command, str(case), "--output", str(output), "--quiet"])
    err = capsys.readouterr().err
    return code, [line for line in err.strip().splitlines() if line]


@pytest.mark.parametrize("mutation", MUTATIONS, ids=[m[0] for m in MUTATIONS])
def test_validate_and_solve_refuse_alike(tmp_path, capsys, mutation):
    _, name, change, fragments = mutation
    data = shipped(name)
    change(data)
    case = tmp_path / f"{name}.yaml"
    case.write_text(yaml.safe_dump(data, sort_keys=False))
    output = tmp_path / "out"
    code, lines = run(capsys, "validate", case, output)
    assert code == 2 and len(lines) == 1, lines          # validate refuses, in one line …
    assert lines[0].startswith(f"sarfe: error: {case}: ") and "Traceback" not in lines[0]
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    solve_code, solve_lines = run(capsys, "solve", case, output)
    assert (solve_code, solve_lines) == (code, lines)     # … and solve refuses the same way
    assert not output.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out.")]
