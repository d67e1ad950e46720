"""Never delete what a case reads (issue 32, item 4): an output folder that contains any input of
the case — the case file, the mesh, the deck and its INCLUDEs, matrix files, curve files — is
refused by `sarfe validate` and `sarfe solve`, with and without --force: exit 2, one line naming
the input, and every file left as it was. ``sarfe solve cases/rattle_rig_deck.yaml --output
meshes --force`` used to delete the engineer's deck and every file beside it."""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from small_cases import tiny

from sarfe.cli import main
from sarfe.pipeline.checks.case_inputs import case_inputs, named_files

ROOT = Path(__file__).resolve().parents[2]


def snapshot(folder: Path) -> dict:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


def refused_everywhere(capsys, case, output, *words):
    """validate and solve, with and without --force: exit 2, one line with ``words``."""
    for command in ("validate", "solve"):
        for extra in ([], ["--force"]):
            code = main([command, str(case), "--output", str(output), "--quiet", *extra])
            err = capsys.readouterr().err
            lines = err.strip().splitlines()
            assert code == 2, err
            assert len(lines) == 1 and lines[0].startswith("sarfe: error: "), err
            assert "Traceback" not in err
            for word in words:
                assert word in lines[0], lines[0]


@pytest.fixture
def deck_copy(tmp_path, monkeypatch):
    """cases/rattle_rig_deck.yaml and meshes/ copied as shipped (the case reads ../meshes/)."""
    shutil.copytree(ROOT / "meshes", tmp_path / "meshes")
    (tmp_path / "cases").mkdir()
    shutil.copy(ROOT / "cases" / "rattle_rig_deck.yaml", tmp_path / "cases")
    monkeypatch.chdir(tmp_path)
    return tmp_path / "cases" / "rattle_rig_deck.yaml"


def test_the_deck_folder_is_never_the_output(deck_copy, capsys):
    before = snapshot(deck_copy.parent.parent)
    for target in ("meshes", Path.cwd() / "meshes", "meshes/../meshes"):
        refused_everywhere(capsys, deck_copy, target, "model.fe.deck", "rattle_rig_deck.bdf",
                           "input of the case", "--force never deletes an input")
    assert snapshot(deck_copy.parent.parent) == before


def test_a_folder_above_an_input_is_refused(tmp_path, deck_copy, capsys):
    """The output may not contain an input at any depth (here: the case and the deck two levels
    down), and a symbolic link to the deck protects the deck's real folder too."""
    before = snapshot(tmp_path)
    work = tmp_path / "work"
    work.mkdir()
    (work / "deck.bdf").symlink_to(tmp_path / "meshes" / "rattle_rig_deck.bdf")
    case = work / "case.yaml"
    case.write_text(deck_copy.read_text().replace("../meshes/rattle_rig_deck.bdf", "deck.bdf"))
    refused_everywhere(capsys, case, tmp_path / "meshes", "model.fe.deck", "deck.bdf")
    assert snapshot(tmp_path / "meshes") == {k[len("meshes/"):]: v for k, v in before.items()
                                             if k.startswith("meshes/")}


def test_mesh_matrix_curve_and_include_folders_are_protected(tmp_path, capsys, monkeypatch):
    """Each kind of input in its own folder; the output named as each of these folders is
    refused, naming the key (or the INCLUDE) that reads the file."""
    monkeypatch.chdir(tmp_path)
    for folder in ("case", "matrices", "curves", "mesh", "deck", "include"):
        (tmp_path / folder).mkdir()
    np.save(tmp_path / "matrices" / "mass.npy", np.eye(2))
    (tmp_path / "curves" / "pad.csv").write_text("0, 0\n1e-3, 10\n2e-3, 40\n")
    matrices = tmp_path / "case" / "matrices.yaml"
    matrices.write_text(tiny(mass="../matrices/mass.npy", contact="{name: pad, type: tabulated, "
                             "normal_dof: 0, gap_m: 1.0e-4, curve_file: ../curves/pad.csv}"))
    refused_everywhere(capsys, matrices, "matrices", "model.matrices.mass", "mass.npy")
    refused_everywhere(capsys, matrices, "curves", "contacts[0].curve_file", "pad.csv")
    shutil.copy(ROOT / "meshes" / "rattle_rig.msh", tmp_path / "mesh" / "rig.msh")
    rig = (ROOT / "cases" / "rattle_rig.yaml").read_text().replace(
        "generator: {name: rattle_rig, mesh_size_m: 0.01, params: {gap: 0.5e-3}}",
        "mesh: ../mesh/rig.msh")
    (tmp_path / "case" / "rig.yaml").write_text(rig)
    refused_everywhere(capsys, tmp_path / "case" / "rig.yaml", "mesh", "model.fe.mesh", "rig.msh")
    # a deck INCLUDE in a folder of its own: found by reading the INCLUDE lines only
    (tmp_path / "include" / "grids.bdf").write_text("$ grids\n")
    (tmp_path / "deck" / "main.bdf").write_text("BEGIN BULK\nINCLUDE '../include/grids.bdf'\n"
                                                "ENDDATA\n")
    deck_case = (ROOT / "cases" / "rattle_rig_deck.yaml").read_text().replace(
        "../meshes/rattle_rig_deck.bdf", "../deck/main.bdf")
    (tmp_path / "case" / "deck.yaml").write_text(deck_case)
    refused_everywhere(capsys, tmp_path / "case" / "deck.yaml", "include",
                       "an INCLUDE of model.fe.deck", "grids.bdf")
    assert (tmp_path / "include" / "grids.bdf").read_text() == "$ grids\n"
    assert np.array_equal(np.load(tmp_path / "matrices" / "mass.npy"), np.eye(2))


def test_case_inputs_lists_every_file_the_case_reads(deck_copy):
    inputs = case_inputs(str(deck_copy))
    root = deck_copy.parent.parent
    assert inputs == {deck_copy: "the case file",
                      root / "meshes" / "rattle_rig_deck.bdf": "model.fe.deck"}


def test_named_files_finds_a_file_under_any_key(tmp_path):
    """A key a later feature adds (a background spectrum file …) is covered without a change
    here; strings that name no file, and output.directory, are not inputs."""
    (tmp_path / "cabin.csv").write_text("25, 30\n")
    (tmp_path / "results").mkdir()
    data = {"name": "x", "erp": {"background_file": "cabin.csv", "surface": "skin"},
            "output": {"directory": "results"}, "contacts": [{"between": ["a", "b"]}]}
    assert named_files(data, tmp_path) == {tmp_path / "cabin.csv": "erp.background_file"}


def test_an_output_beside_the_inputs_is_fine(deck_copy, capsys):
    """A new folder inside the deck's folder holds no input: validate accepts it."""
    code = main(["validate", str(deck_copy), "--output", "meshes/results", "--quiet"])
    assert code == 0, capsys.readouterr().err


def test_batch_never_writes_into_a_folder_holding_an_input(tmp_path, capsys, monkeypatch):
    """`sarfe batch` (written in place: it never deletes, but would overwrite a summary.json)
    refuses a folder holding a file a variant reads, even with --force."""
    monkeypatch.chdir(tmp_path)
    for folder in ("case", "matrices"):
        (tmp_path / folder).mkdir()
    np.save(tmp_path / "matrices" / "mass.npy", np.eye(2))
    case = tmp_path / "case" / "tiny.yaml"
    case.write_text(tiny(mass="../matrices/mass.npy"))
    before = snapshot(tmp_path / "matrices")
    code = main(["batch", str(case), "--workers", "0", "--output", "matrices", "--force"])
    err = capsys.readouterr().err
    assert code == 2 and "model.matrices.mass" in err and "input of the case" in err, err
    assert snapshot(tmp_path / "matrices") == before
