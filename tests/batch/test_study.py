"""Study files, parameter paths and deterministic variant generation."""
import math
import pathlib

import numpy as np
import pytest

from sarfe.batch.paths import PathError, set_path
from sarfe.batch.variants import StudyError, collect_variants, load_study, parameter_sets, read_yaml

HERE = pathlib.Path(__file__).resolve().parent

CASE = {"excitation": {"forces": [{"force_N": 1.0}]},
        "contacts": [{"name": "pocket_1", "gap_m": 1e-4}, {"name": "pocket_2", "gap_m": 2e-4}]}


def write(tmp_path, text, name="study.yaml"):
    (tmp_path / "case.yaml").write_text((HERE / "fake_case.yaml").read_text())
    path = tmp_path / name
    path.write_text(text)
    return path


def test_paths_index_name_wildcard_and_copy():
    assert set_path(CASE, "contacts[1].gap_m", 3e-4)["contacts"][1]["gap_m"] == 3e-4
    assert set_path(CASE, "contacts[-1].gap_m", 4e-4)["contacts"][1]["gap_m"] == 4e-4
    out = set_path(CASE, "contacts[name=pocket_2].gap_m", 5e-4)
    assert out["contacts"][1]["gap_m"] == 5e-4 and CASE["contacts"][1]["gap_m"] == 2e-4  # copy
    out = set_path(CASE, "contacts[*].friction_coefficient", 0.4)
    assert [c["friction_coefficient"] for c in out["contacts"]] == [0.4, 0.4]
    assert set_path(CASE, "excitation.forces[0].force_N", 3.0)["excitation"]["forces"][0]["force_N"] == 3.0


@pytest.mark.parametrize("path, words", [
    ("contacts[2].gap_m", "out of range"),
    ("contacts[name=nope].gap_m", "no list item"),
    ("solver.harmonics", "no key 'solver'"),
    ("contacts[0]..gap", "cannot parse"),
    ("contacts[0]", "plain key"),
])
def test_path_errors_name_the_problem(path, words):
    with pytest.raises(PathError, match=words):
        set_path(CASE, path, 1.0)


def test_grid_is_cartesian_product_last_fastest(tmp_path):
    path = write(tmp_path, """
base_case: case.yaml
variations:
  grid:
    contacts[0].gap_m: [1.0e-4, 2.0e-4]
    contacts[*].friction_coefficient: [0.2, 0.3, 0.4]
""")
    variants = collect_variants(path)
    assert [tuple(v.parameters.values()) for v in variants] == [
        (1e-4, 0.2), (1e-4, 0.3), (1e-4, 0.4), (2e-4, 0.2), (2e-4, 0.3), (2e-4, 0.4)]
    assert variants[4].case["contacts"][0]["gap_m"] == 2e-4
    assert variants[4].case["contacts"][1]["friction_coefficient"] == 0.3
    assert len({v.id for v in variants}) == 6 and all(v.source == "study" for v in variants)


def test_list_and_overrides(tmp_path):
    path = write(tmp_path, """
name: two
base_case: case.yaml
overrides: {excitation.force_N: 2.5}
variations:
  list:
    - {'contacts[name=pocket_1].gap_m': 0.0}
    - {'contacts[name=pocket_2].gap_m': 1e-3, 'model.damping_ratio': 0.05}
""")
    first, second = collect_variants(path)
    assert first.case["excitation"]["force_N"] == second.case["excitation"]["force_N"] == 2.5
    assert second.case["contacts"][1]["gap_m"] == 1e-3 and second.case["model"]["damping_ratio"] == 0.05
    assert first.source == "two" and first.case_dir == str(tmp_path.resolve())


MC = """
base_case: case.yaml
variations:
  monte_carlo:
    samples: 400
    seed: {seed}
    parameters:
      contacts[0].gap_m: {{distribution: truncated_normal, mean: 1.0e-4, std: 1.0e-4, low: 0.0, high: 2.0e-4}}
      contacts[1].gap_m: {{distribution: normal, mean: 3.0e-4, std: 1.0e-5}}
      contacts[*].friction_coefficient: {{distribution: uniform, low: 0.2, high: 0.5}}
      contacts[0].normal_stiffness_N_m: {{distribution: lognormal, median: 1.0e6, log_std: 0.5}}
"""


def test_selected_key_missing_in_base_case_is_added(tmp_path):
    path = write(tmp_path, """
base_case: case.yaml
variations:
  grid:
    contacts[name=pocket_2].tolerance_m: [1.0e-5]
""")
    (variant,) = collect_variants(path)
    assert variant.case["contacts"][1]["tolerance_m"] == 1e-5 and "tolerance_m" not in variant.case["contacts"][0]


def test_monte_carlo_is_deterministic_with_seed(tmp_path):
    a = collect_variants(write(tmp_path, MC.format(seed=7)))
    b = collect_variants(write(tmp_path, MC.format(seed=7)))
    c = collect_variants(write(tmp_path, MC.format(seed=8)))
    assert [v.parameters for v in a] == [v.parameters for v in b]
    assert [v.id for v in a] == [v.id for v in b]
    assert not {v.id for v in a} & {v.id for v in c}
    values = {p: np.array([v.parameters[p] for v in a]) for p in a[0].parameters}
    gap = values["contacts[0].gap_m"]
    assert gap.min() >= 0.0 and gap.max() <= 2e-4 and abs(gap.mean() - 1e-4) < 1e-5  # symmetric truncation
    assert abs(values["contacts[1].gap_m"].std() - 1e-5) < 1.5e-6
    mu = values["contacts[*].friction_coefficient"]
    assert mu.min() >= 0.2 and mu.max() < 0.5
    stiffness = values["contacts[0].normal_stiffness_N_m"]
    assert stiffness.min() > 0 and abs(np.median(np.log(stiffness)) - math.log(1e6)) < 0.1
    # the first draws, pinned: a change in the generator would silently change every study
    first = parameter_sets(load_study(write(tmp_path, MC.format(seed=7))))[0]
    assert first == a[0].parameters


def test_variant_id_ignores_key_order_and_comments(tmp_path):
    path = write(tmp_path, "base_case: case.yaml\nvariations: {list: [{'contacts[0].gap_m': 1.0e-4}]}\n")
    (variant,) = collect_variants(path)
    text = (tmp_path / "case.yaml").read_text()
    (tmp_path / "case.yaml").write_text("# a comment\n" + text)
    assert collect_variants(path)[0].id == variant.id
    (tmp_path / "case.yaml").write_text(text.replace("force_N: 1.0", "force_N: 1.5"))
    assert collect_variants(path)[0].id != variant.id  # another base case → other ids


@pytest.mark.parametrize("text, words", [
    ("base_case: case.yaml\nvariations: {grid: {'contacts[0].gap_m': [1]}}\nseeds: 3\n", "unknown key.*seeds"),
    ("base_case: case.yaml\nvariations: {grid: {'contacts[0].gap_m': [1]}, list: [{'a': 1}]}\n", "variations"),
    ("base_case: case.yaml\nvariations: {monte_carlo: {samples: 3, seed: 1, parameters: "
     "{'contacts[0].gap_m': {distribution: normal, mean: 1}}}}\n", "normal needs exactly: mean, std"),
    ("base_case: case.yaml\nvariations: {monte_carlo: {samples: 3, seed: 1, parameters: "
     "{'contacts[0].gap_m': {distribution: weibull, k: 1}}}}\n", "distribution must be one of"),
    ("base_case: case.yaml\nvariations: {monte_carlo: {samples: 3, seed: 1, parameters: "
     "{'contacts[0].gap_m': {distribution: uniform, low: 2, high: 1}}}}\n", "low must be < high"),
    ("base_case: case.yaml\nvariations: {grid: {'contacts[name=pocket_9].gap_m': [1]}}\n", "no list item"),
    ("base_case: missing.yaml\nvariations: {grid: {'a': [1]}}\n", "missing.yaml: cannot read"),
    ("base_case: case.yaml\nvariations: {list: [{'contacts[0].gap_m': 1}, {'contacts[0].gap_m': 1}]}\n", "identical"),
])
def test_bad_study_files_are_errors_naming_the_key(tmp_path, text, words):
    with pytest.raises(StudyError, match=words):
        collect_variants(write(tmp_path, text))


def test_yaml_exponent_without_dot_is_a_number(tmp_path):
    path = tmp_path / "x.yaml"
    path.write_text("a: 1e-4\nb: 2E+3\nc: '1e-4'\nd: 1.0\n")
    assert read_yaml(path) == {"a": 1e-4, "b": 2e3, "c": "1e-4", "d": 1.0}


def test_plain_case_files_are_one_variant_each(tmp_path):
    (tmp_path / "a.yaml").write_text((HERE / "fake_case.yaml").read_text())
    (tmp_path / "b.yaml").write_text((HERE / "fake_case.yaml").read_text().replace("1.0e-4", "2.0e-4"))
    variants = collect_variants([tmp_path / "a.yaml", tmp_path / "b.yaml"])
    assert [v.index for v in variants] == [0, 1] and variants[0].parameters == {}
    assert variants[0].source.endswith("a.yaml") and variants[0].id != variants[1].id
