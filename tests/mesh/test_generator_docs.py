"""Every generator's ``params`` is documented (issue 31, item 6): docs/case-file.md has a table per
generator naming each parameter its ``generate``/``spec`` takes, with the code's own default, and
lists the groups the generator makes (checked against a generated mesh)."""
from __future__ import annotations

import importlib
import inspect
import re
from pathlib import Path

import pytest

from sarfe.mesh.cache import cached_mesh
from sarfe.mesh.generators import GENERATORS, parameter_names

DOC = (Path(__file__).resolve().parents[2] / "docs" / "case-file.md").read_text()
COARSE_M = {"rattle_rig": 0.02, "squeak_rig": 0.02, "door_trim": 0.04, "instrument_panel": 0.04}


def section(name: str) -> str:
    start = DOC.index(f"**`{name}`**")
    following = [DOC.find(f"**`{other}`**", start + 1) for other in GENERATORS]
    following = [i for i in following if i > start] + [DOC.index("## `model.fe.deck`")]
    return DOC[start:min(following)]


def defaults(name: str) -> dict:
    module = importlib.import_module(f"sarfe.mesh.generators.{name}")
    out = {}
    for function in (module.generate, getattr(module, "spec", None)):
        if function is not None:
            out |= {p.name: p.default for p in inspect.signature(function).parameters.values()
                    if p.default is not inspect.Parameter.empty}
    return out


@pytest.mark.parametrize("name", GENERATORS)
def test_every_param_is_documented_with_its_default(name):
    text = section(name)
    rows = dict(re.findall(r"^\| `(\w+)` \| ([^|]+) \|", text, flags=re.M))
    assert set(rows) == set(parameter_names(name)), (set(rows) ^ set(parameter_names(name)))
    for param, default in defaults(name).items():
        if param in rows:
            assert float(rows[param]) == pytest.approx(float(default), rel=1e-12), param


@pytest.mark.parametrize("name", GENERATORS)
def test_the_documented_groups_exist(tmp_path, monkeypatch, name):
    monkeypatch.setenv("SARFE_MESH_CACHE", str(tmp_path / "cache"))
    text = section(name).split("Groups:", 1)[1]
    mesh = cached_mesh(name, COARSE_M[name])
    groups = set(mesh.node_groups) | set(mesh.element_groups)
    for word in re.findall(r"`([a-z_0-9.]+)`", text):
        span = re.fullmatch(r"(.*?)(\d+)\.\.(\d+)", word)
        names = ([f"{span[1]}{i}" for i in range(int(span[2]), int(span[3]) + 1)] if span
                 else [word])
        for group in names:      # a group, or a contact spot (its pair of node groups)
            assert group in groups or f"contact_{group}_a" in groups, (name, group)
