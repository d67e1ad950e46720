"""Bounded parsing (issue 32, item 5): the YAML reader's safety limits (sarfe.case.read).

A 2 kB case file of nested aliases ("billion laughs") took 31 s and 5.8 GB at 8 levels and then
a MemoryError traceback, and never answered at 9 levels; deep nesting ended in a RecursionError.
Each is now one line naming the file and the limit, exit 2, from `sarfe validate` and `sarfe
solve`. The time bound is a safety limit on the parse alone (process time, generous: the parse
takes milliseconds), not a performance assert on the solver.
"""
from __future__ import annotations

import time
from pathlib import Path

import pytest
import yaml

from sarfe.case.errors import CaseError
from sarfe.case.read import (MAX_ALIAS_EXPANSION, MAX_CASE_FILE_BYTES, MAX_YAML_ALIASES,
                             MAX_YAML_DEPTH, CaseLoader, load_case, read_yaml)
from sarfe.cli import main

ROOT = Path(__file__).resolve().parents[2]
PARSE_LIMIT_S = 1.0      # process time of read_yaml on a hostile 2 kB file


def laughs(levels: int) -> str:
    """A valid-looking case whose description is a 9^levels-fold expansion of aliases."""
    lines = ["name: laughs", "model:", "  fe:", "    generator:", "      name: rattle_rig",
             "      mesh_size_m: 0.01", "      params:",
             "        a0: &a0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    for i in range(1, levels + 1):
        lines.append(f"        a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]")
    return "\n".join(lines) + "\n"


def one_line_refusal(capsys, case, *words):
    for command in ("validate", "solve"):
        code = main([command, str(case), "--output", str(case.parent / "out"), "--quiet"])
        err = capsys.readouterr().err
        lines = err.strip().splitlines()
        assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
        assert lines[0].startswith(f"sarfe: error: {case}: "), lines[0]
        for word in words:
            assert word in lines[0], lines[0]
        assert not (case.parent / "out").exists()


@pytest.mark.parametrize("levels", [8, 9])
def test_billion_laughs_is_refused_in_under_a_second(tmp_path, capsys, levels):
    case = tmp_path / "laughs.yaml"
    case.write_text(laughs(levels))
    assert case.stat().st_size < 2500
    clock = time.process_time()
    with pytest.raises(CaseError, match="billion laughs") as error:
        read_yaml(case)
    assert time.process_time() - clock < PARSE_LIMIT_S
    assert f"{9 ** levels:.2g}"[:3] in str(error.value) or "e+0" in str(error.value)
    one_line_refusal(capsys, case, "safety limits", "aliases expand to", "billion laughs")


def test_deep_nesting_is_refused(tmp_path, capsys):
    case = tmp_path / "deep.yaml"
    case.write_text("name: deep\nmodel: " + "[" * 5000 + "]" * 5000 + "\n")
    clock = time.process_time()
    with pytest.raises(CaseError, match=f"nested more than {MAX_YAML_DEPTH} levels"):
        read_yaml(case)
    assert time.process_time() - clock < PARSE_LIMIT_S
    one_line_refusal(capsys, case, "nested more than", "(line 2)")


def test_too_many_aliases_and_a_recursive_alias(tmp_path, capsys):
    many = tmp_path / "many.yaml"
    many.write_text("name: many\nx: &x 1\ny: [" + ", ".join(["*x"] * (MAX_YAML_ALIASES + 1))
                    + "]\n")
    one_line_refusal(capsys, many, f"more than {MAX_YAML_ALIASES} aliases", "(line 3)")
    recursive = tmp_path / "recursive.yaml"
    recursive.write_text("name: r\nmodel: &m [*m]\n")
    one_line_refusal(capsys, recursive, "an alias inside its own anchor")


def test_case_file_size_and_kind(tmp_path, capsys):
    big = tmp_path / "big.yaml"
    row = "[" + ", ".join(["1.0e+00"] * 1000) + "]"
    with open(big, "w") as stream:
        stream.write("name: big\nmodel:\n  matrices:\n    mass:\n")
        while stream.tell() <= MAX_CASE_FILE_BYTES:
            stream.write(f"      - {row}\n")
    one_line_refusal(capsys, big, "larger than 1 MiB", ".npz")
    folder = tmp_path / "folder.yaml"
    folder.mkdir()
    one_line_refusal(capsys, folder, "not a regular file")
    if Path("/dev/zero").exists():      # endless: only the first bytes may be read
        for command in ("validate", "solve"):
            assert main([command, "/dev/zero", "--quiet"]) == 2
            assert "not a regular file" in capsys.readouterr().err


def test_anchors_of_a_real_case_still_read(tmp_path):
    """A shared material by anchor and merge key (what a user writes) is well within the limits,
    and a shared alias expands below MAX_ALIAS_EXPANSION."""
    text = (ROOT / "cases" / "rattle_rig.yaml").read_text().replace(
        "part_plate: {E_Pa: 2.2e9, nu: 0.37, rho_kg_m3: 1050}",
        "part_plate: &abs {E_Pa: 2.2e9, nu: 0.37, rho_kg_m3: 1050}").replace(
        "part_beam:  {E_Pa: 2.1e11, nu: 0.30, rho_kg_m3: 7850}",
        "part_beam: {<<: *abs, E_Pa: 2.1e11, nu: 0.30, rho_kg_m3: 7850}")
    case = tmp_path / "anchors.yaml"
    case.write_text(text)
    config = load_case(case).config
    assert config.model.fe.materials["part_beam"].E_Pa == 2.1e11
    wide = "name: w\nrow: &r [" + ", ".join(["1"] * 1000) + "]\nrows: [" + \
        ", ".join(["*r"] * (MAX_ALIAS_EXPANSION // 1000 - 1)) + "]\n"
    data = yaml.load(wide, Loader=CaseLoader)
    assert len(data["rows"]) == MAX_ALIAS_EXPANSION // 1000 - 1
