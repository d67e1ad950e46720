"""A corpus of bad inputs made from the shipped cases (cases/) and meshes (meshes/*.msh): non-finite
numbers, wrong signs, wrong units, degenerate elements, unheld structures, malformed YAML and mesh
files, missing files, wrong types, unknown groups. EVERY one must give, in both `sarfe validate`
and `sarfe solve`: exit code 2, one line on stderr naming the file and the key or element, no
traceback, and no output folder (issue 11). The data are generated here from the shipped files."""
from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from sarfe.cli import main
from sarfe.case.read import CaseLoader

ROOT = Path(__file__).resolve().parents[2]
CASES = ROOT / "cases"


# ------------------------------------------------------------------------------ base inputs
def lumped() -> dict:
    return yaml.load((CASES / "lumped_rattle.yaml").read_text(), Loader=CaseLoader)


def rig() -> dict:
    """cases/rattle_rig.yaml reading the shipped 5 mm mesh (as ASCII MSH 2.2: rig.msh)."""
    data = yaml.load((CASES / "rattle_rig.yaml").read_text(), Loader=CaseLoader)
    data["model"]["fe"].pop("generator")
    data["model"]["fe"]["mesh"] = "rig.msh"
    return data


def squeak() -> dict:
    return yaml.load((CASES / "squeak_rig.yaml").read_text(), Loader=CaseLoader)


@pytest.fixture(scope="module")
def msh22(tmp_path_factory) -> str:
    """meshes/rattle_rig.msh rewritten as ASCII MSH 2.2 (so that lines can be edited)."""
    from sarfe.mesh.gmsh_model import gmsh_session

    path = tmp_path_factory.mktemp("mesh") / "rig.msh"
    with gmsh_session() as gmsh:
        gmsh.open(str(ROOT / "meshes" / "rattle_rig.msh"))
        gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
        gmsh.option.setNumber("Mesh.Binary", 0)
        gmsh.write(str(path))
    return path.read_text()


# --------------------------------------------------------------------------- mesh mutations
def _sections(text):
    lines = text.splitlines()
    n0 = lines.index("$Nodes")
    e0 = lines.index("$Elements")
    nodes = lines[n0 + 2:lines.index("$EndNodes")]
    elements = lines[e0 + 2:lines.index("$EndElements")]
    return lines[:n0], nodes, elements, lines[lines.index("$EndElements") + 1:]


def _join(head, nodes, elements, tail):
    return "\n".join(head + ["$Nodes", str(len(nodes)), *nodes, "$EndNodes", "$Elements",
                             str(len(elements)), *elements, "$EndElements", *tail]) + "\n"


def _triangles(elements):
    return [i for i, line in enumerate(elements) if line.split()[1] == "2"]


def _plate_triangle(elements):
    """Index of the first triangle of the last physical surface (the plate)."""
    tris = _triangles(elements)
    return tris[-1]


def degenerate_repeated_node(text):
    head, nodes, elements, tail = _sections(text)
    i = _plate_triangle(elements)
    parts = elements[i].split()
    parts[-1] = parts[-3]                      # (a, b, a): zero area
    elements[i] = " ".join(parts)
    return _join(head, nodes, elements, tail)


def degenerate_collinear(text):
    """A new triangle through three nodes on one straight plate edge (y = −0.075, z = 0)."""
    head, nodes, elements, tail = _sections(text)
    edge = [line.split()[0] for line in nodes
            if abs(float(line.split()[2]) + 0.075) < 1e-12 and abs(float(line.split()[3])) < 1e-12]
    template = elements[_plate_triangle(elements)].split()
    tags = template[2:3 + int(template[2])]
    new_id = max(int(line.split()[0]) for line in elements) + 1
    elements.append(" ".join([str(new_id), "2", *tags, *edge[:3]]))
    return _join(head, nodes, elements, tail)


def duplicate_triangle(text):
    """A second triangle on the same three nodes (reversed order, its own id)."""
    head, nodes, elements, tail = _sections(text)
    parts = elements[_plate_triangle(elements)].split()
    new_id = max(int(line.split()[0]) for line in elements) + 1
    ntags = int(parts[2])
    a, b, c = parts[3 + ntags:]
    elements.append(" ".join([str(new_id), "2", *parts[2:3 + ntags], a, c, b]))
    return _join(head, nodes, elements, tail)


def coincident_node(text):
    """A crack: one plate triangle uses a new node placed exactly on an existing one."""
    head, nodes, elements, tail = _sections(text)
    i = _plate_triangle(elements)
    parts = elements[i].split()
    old = parts[-1]
    x, y, z = next(line.split()[1:] for line in nodes if line.split()[0] == old)
    new_node = str(max(int(line.split()[0]) for line in nodes) + 1)
    nodes.append(f"{new_node} {x} {y} {z}")
    parts[-1] = new_node
    elements[i] = " ".join(parts)
    return _join(head, nodes, elements, tail)


def no_triangles(text):
    head, nodes, elements, tail = _sections(text)
    return _join(head, nodes, [e for e in elements if e.split()[1] != "2"], tail)


def node_out_of_range(text):
    head, nodes, elements, tail = _sections(text)
    i = _plate_triangle(elements)
    parts = elements[i].split()
    parts[-1] = "999999"
    elements[i] = " ".join(parts)
    return _join(head, nodes, elements, tail)


def truncated(text):
    return text[: len(text) // 2]


# ------------------------------------------------------------------------------- the corpus
def setitem(path, value):
    def change(data):
        node = data
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = value
    return change


def delitem(path):
    def change(data):
        node = data
        for key in path[:-1]:
            node = node[key]
        del node[path[-1]]
    return change


NAN, INF = float("nan"), float("inf")
# (id, base, change of the data, mesh text change or None, raw text instead of YAML or None,
#  fragments the one error line must contain)
CORPUS = [
    # non-finite numbers
    ("nan-gap", lumped, setitem(("contacts", 0, "gap_m"), NAN), None, None,
     ["contacts[0].gap_m", "finite", "(line"]),
    ("inf-amplitude", lumped, setitem(("excitation", "base_acceleration", "amplitude_m_s2"), INF),
     None, None, ["amplitude_m_s2", "finite"]),
    ("-inf-stiffness", lumped, setitem(("model", "matrices", "stiffness", 0, 0), -INF), None, None,
     ["model.matrices.stiffness[0][0]", "finite"]),
    ("nan-zeta", lumped, setitem(("damping", "modal_zeta"), NAN), None, None, ["damping.modal_zeta"]),
    ("nan-tolerance", lumped, setitem(("solver", "tolerance"), NAN), None, None, ["solver.tolerance"]),
    ("nan-sweep", lumped, setitem(("excitation", "sweep", "start_hz"), NAN), None, None,
     ["sweep.start_hz"]),
    ("inf-area", lumped, setitem(("erp", "areas_m2", 0), INF), None, None, ["erp.areas_m2[0]"]),
    ("inf-contact-stiffness", rig, setitem(("contacts", 0, "normal_stiffness_N_m"), INF), None, None,
     ["contacts[0].normal_stiffness_N_m"]),
    ("nan-thickness", rig, setitem(("model", "fe", "thickness_m", "part_plate"), NAN), None, None,
     ["thickness_m.part_plate"]),
    ("nan-force", rig, setitem(("excitation", "forces", 0, "force_N"), NAN), None, None,
     ["excitation.forces[0].force_N"]),
    # signs
    ("negative-amplitude", lumped, setitem(("excitation", "base_acceleration", "amplitude_m_s2"), -3.0),
     None, None, ["amplitude_m_s2", ">= 0"]),
    ("negative-force", rig, setitem(("excitation", "forces", 0, "force_N"), -0.05), None, None,
     ["excitation.forces[0].force_N", ">= 0"]),
    ("negative-stiffness", lumped, setitem(("contacts", 0, "normal_stiffness_N_m"), -1e6), None,
     None, ["contacts[0].normal_stiffness_N_m"]),
    ("negative-zeta", lumped, setitem(("damping", "modal_zeta"), -0.03), None, None,
     ["damping.modal_zeta"]),
    ("negative-friction", lumped, setitem(("contacts", 1, "friction_coefficient"), -0.4), None, None,
     ["contacts[1].friction_coefficient"]),
    # wrong units
    ("thickness-in-mm", rig, setitem(("model", "fe", "thickness_m", "part_plate"), 2.5), None, None,
     ["thickness_m.part_plate", "given in mm"]),
    ("thickness-too-thin", rig, setitem(("model", "fe", "thickness_m", "part_beam"), 1.5e-6), None,
     None, ["thickness_m.part_beam", "thin"]),
    ("modulus-in-GPa", rig, setitem(("model", "fe", "materials", "part_plate", "E_Pa"), 2.2), None,
     None, ["part_plate.E_Pa", "pascals"]),
    ("density-in-t-mm3", rig, setitem(("model", "fe", "materials", "part_beam", "rho_kg_m3"), 7.85e-9),
     None, None, ["part_beam.rho_kg_m3"]),
    ("mesh-units-mm", rig, setitem(("model", "fe", "mesh_units"), "mm"), None, None,
     ["model.fe.mesh_units"]),
    ("frequency-1e9", lumped, setitem(("excitation", "sweep", "end_hz"), 1e9), None, None,
     ["excitation.sweep", "audible"]),
    ("mesh-size-in-mm", squeak, setitem(("model", "fe", "generator", "mesh_size_m"), 10.0), None,
     None, ["mesh_size_m", "metres"]),
    # degenerate elements and broken meshes
    ("zero-area-repeated-node", rig, None, degenerate_repeated_node, None,
     ["model.fe.mesh", "zero-area triangle"]),
    ("zero-area-collinear", rig, None, degenerate_collinear, None, ["zero-area triangle", "nodes"]),
    ("duplicate-triangle", rig, None, duplicate_triangle, None, ["duplicate triangle", "repeats"]),
    ("coincident-node-crack", rig, None, coincident_node, None, ["coincident nodes", "crack"]),
    ("mesh-without-triangles", rig, None, no_triangles, None, ["model.fe.mesh", "rig.msh"]),
    ("mesh-node-out-of-range", rig, None, node_out_of_range, None, ["model.fe.mesh", "rig.msh"]),
    ("mesh-truncated", rig, None, truncated, None, ["model.fe.mesh", "rig.msh"]),
    ("mesh-garbage", rig, None, lambda t: "this is not a mesh\n", None, ["model.fe.mesh"]),
    ("mesh-empty-file", rig, None, lambda t: "", None, ["model.fe.mesh"]),
    # structure not held
    ("plate-not-held", rig, setitem(("model", "fe", "fixed"), ["clamp_beam"]), None, None,
     ["model.fe.fixed", "not held"]),
    ("beam-not-held", rig, setitem(("model", "fe", "fixed"), ["clamp_plate"]), None, None,
     ["model.fe.fixed", "not held"]),
    ("squeak-beam-not-held", squeak, setitem(("model", "fe", "fixed"), ["clamp_plate"]), None, None,
     ["not held"]),
    # malformed YAML
    ("yaml-unclosed-bracket", None, None, None,
     lambda t: t.replace("[[0.2, 0.0, 0.0]", "[[0.2, 0.0, 0.0", 1), ["malformed YAML at line"]),
    ("yaml-bad-indent", None, None, None, lambda t: t.replace("\n  matrices:", "\n matrices:\n  x: 1", 1),
     ["malformed YAML"]),
    ("yaml-duplicate-key", None, None, None,
     lambda t: t.replace("    gap_m: 1.0e-4\n", "    gap_m: 1.0e-4\n    gap_m: 2.0e-4\n", 1),
     ["contacts[0].gap_m", "duplicate key"]),
    ("yaml-empty", None, None, None, lambda t: "", ["empty"]),
    ("yaml-list", None, None, None, lambda t: "- a\n- b\n", ["mapping"]),
    ("yaml-binary", None, None, None, lambda t: b"\xff\xfe\x00garbage", ["cannot read case file"]),
    ("yaml-tab", None, None, None, lambda t: t.replace("\n  matrices:", "\n\tmatrices:", 1),
     ["malformed YAML"]),
    # missing files
    ("mesh-missing", rig, setitem(("model", "fe", "mesh"), "nowhere.msh"), None, None,
     ["model.fe.mesh", "not found"]),
    ("matrix-missing", lumped, setitem(("model", "matrices", "mass"), "nowhere.npz"), None, None,
     ["model.matrices.mass", "not found"]),
    ("mesh-wrong-suffix", rig, setitem(("model", "fe", "mesh"), "rig.stl"), None, None,
     ["model.fe.mesh", ".msh"]),
    # wrong types and shapes
    ("gap-as-text", lumped, setitem(("contacts", 0, "gap_m"), "one mm"), None, None,
     ["contacts[0].gap_m", "expected a number"]),
    ("harmonics-float", lumped, setitem(("solver", "harmonics"), 2.5), None, None,
     ["solver.harmonics", "integer"]),
    ("contacts-mapping", lumped, setitem(("contacts",), {"a": 1}), None, None, ["contacts"]),
    ("frequencies-empty", lumped, lambda d: (d["excitation"].pop("sweep"),
                                             d["excitation"].update(frequency_hz=[])), None, None,
     ["excitation.frequency_hz"]),
    ("unknown-key", lumped, lambda d: d["contacts"][0].update(gap_mm=1.0), None, None,
     ["contacts[0].gap_mm", "unknown key"]),
    ("mass-not-square", lumped, setitem(("model", "matrices", "mass"), [[0.2, 0.0], [0.0, 0.5, 0.0]]),
     None, None, ["model.matrices.mass"]),
    ("dof-out-of-range", lumped, setitem(("contacts", 0, "normal_dof", "dof"), 7), None, None,
     ["contacts[0].normal_dof.dof", "out of range"]),
    ("missing-excitation", lumped, delitem(("excitation",)), None, None, ["excitation"]),
    # groups
    ("unknown-fixed-group", rig, setitem(("model", "fe", "fixed"), ["clamp_nowhere"]), None, None,
     ["model.fe.fixed[0]", "clamp_nowhere"]),
    ("unknown-contact-group", rig, setitem(("contacts", 0, "between", 1), "contact_none"), None, None,
     ["contacts[0].between[1]", "contact_none"]),
    ("unknown-erp-surface", rig, setitem(("erp", "surface"), "roof"), None, None,
     ["erp.surface", "roof"]),
    ("unknown-thickness-group", rig, lambda d: d["model"]["fe"]["thickness_m"].pop("part_beam"),
     None, None, ["model.fe.thickness_m", "no listed element group"]),
    # inputs that used to solve into nonsense (review8)
    ("pair-with-itself", rig, lambda d: (d["contacts"][0].pop("between"),
                                         d["contacts"][0].update(pairs=[[5, 5]])), None, None,
     ["contacts[0].pairs[0]", "node 5 is paired with itself"]),
    ("force-on-clamped-group", rig, setitem(("excitation", "forces", 0, "group"), "clamp_beam"),
     None, None, ["excitation.forces[0].group", "the force on group clamp_beam acts on no free "
                  "DOF: all of its DOFs are fixed"]),
    ("stiffness-all-zero", lumped, setitem(("model", "matrices", "stiffness"),
                                           [[0.0] * 3 for _ in range(3)]), None, None,
     ["model.matrices.stiffness", "not held", "null space of size 2 of 3 DOFs", "DOF(s) 0, 1"]),
    ("accuracy-negative", lumped, setitem(("solver", "accuracy"), {"erp_db": -1}), None, None,
     ["solver.accuracy.erp_db", "must be > 0, got -1"]),
    ("workers-zero", lumped, setitem(("solver", "workers"), 0), None, None,
     ["solver.workers", "must be >= 1, got 0"]),
    ("workers-text", lumped, setitem(("solver", "workers"), "many"), None, None,
     ["solver.workers", "must be one of 'auto' or an integer, got 'many'"]),
    ("generator-param-typo", squeak, setitem(("model", "fe", "generator", "params"),
                                             {"plate_sizee": 0.1}), None, None,
     ["model.fe.generator.params.plate_sizee", "unknown parameter of generator squeak_rig",
      "did you mean 'plate_size'?", "valid: plate_size"]),
    ("tabulated-preload-above-plateau", rig, lambda d: d["contacts"][0].update(
        type="tabulated", curve=[[0, 0], [1e-3, 1.0], [2e-3, 1.0]], preload_N=2.0) or [
        d["contacts"][0].pop(k) for k in ("normal_stiffness_N_m",)], None, None,
     ["contacts[0].preload_N", "2 N is above the curve's largest force 1 N"]),
]


def make_input(tmp_path, msh22, entry) -> Path:
    name, base, change, mesh_change, raw, _ = entry
    case = tmp_path / "case.yaml"
    if raw is not None:
        text = raw((CASES / "lumped_rattle.yaml").read_text())
        case.write_bytes(text if isinstance(text, bytes) else text.encode())
        return case
    data = base()
    if change is not None:
        change(data)
    case.write_text(yaml.safe_dump(data, sort_keys=False))
    if base is rig:
        (tmp_path / "rig.msh").write_text(mesh_change(msh22) if mesh_change else msh22)
    return case


def assert_refused(code, err, case, fragments, output):
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1, err
    line = lines[0]
    assert line.startswith("sarfe: error: ") and "Traceback" not in err
    assert str(case) in line or "rig.msh" in line, line          # names the file
    for fragment in fragments:
        assert fragment in line, line
    assert not output.exists()
    assert not [p for p in output.parent.iterdir() if p.name.startswith(f".{output.name}.")]


def test_corpus_is_large_enough():
    assert len(CORPUS) >= 40 and len({c[0] for c in CORPUS}) == len(CORPUS)


@pytest.mark.parametrize("entry", CORPUS, ids=[c[0] for c in CORPUS])
def test_bad_input_refused_by_validate_and_solve(tmp_path, msh22, capsys, monkeypatch, entry):
    monkeypatch.setenv("SARFE_MESH_CACHE", str(tmp_path.parent / "mesh-cache"))
    case = make_input(tmp_path, msh22, entry)
    output = tmp_path / "out"
    for command in ("validate", "solve"):
        code = main([command, str(case), "--output", str(output), "--quiet"])
        assert_refused(code, capsys.readouterr().err, case, entry[-1], output)


@pytest.mark.parametrize("name", ["nan-gap", "coincident-node-crack", "yaml-unclosed-bracket",
                                  "plate-not-held"])
def test_bad_input_real_process(tmp_path, msh22, name):
    """The installed entry point: exit code 2 and one stderr line, as a user sees it."""
    entry = next(c for c in CORPUS if c[0] == name)
    case = make_input(tmp_path, msh22, entry)
    env = dict(os.environ, PYTHONPATH=str(ROOT), SARFE_MESH_CACHE=str(tmp_path / "cache"))
    for command in ("validate", "solve"):
        proc = subprocess.run([sys.executable, "-m", "sarfe.cli", command, str(case), "--output",
                               str(tmp_path / "out")], env=env, capture_output=True, text=True,
                              timeout=300, cwd=tmp_path)
        # progress lines ("sarfe: checking the case: … …") may precede the one error line
        errors = "\n".join(line for line in proc.stderr.splitlines() if not line.endswith(" …"))
        assert_refused(proc.returncode, errors, case, entry[-1], tmp_path / "out")
        assert "Traceback" not in proc.stderr and "linear stage" not in proc.stderr


def test_shipped_cases_pass_the_same_checks(tmp_path, msh22, capsys):
    """The corpus' bases themselves are valid (the mutations, not the bases, are refused)."""
    for base in (lumped, rig):
        case = make_input(tmp_path, msh22, ("base", base, None, None, None, []))
        assert main(["validate", str(case), "--output", str(tmp_path / "out")]) == 0, \
            capsys.readouterr().err
        assert not re.search(r"warning|error", capsys.readouterr().err)
