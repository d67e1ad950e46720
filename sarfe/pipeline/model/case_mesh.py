"""The mesh of a generator or mesh-file FE case, in metres: ``model.fe.mesh`` read (with its
``mesh_units``) or ``model.fe.generator`` generated through the checksummed mesh cache.

    load_case_mesh(case) -> PanelMesh     CaseError naming model.fe.mesh / generator on failure

A mesh whose span (bounding-box diagonal) lies outside :data:`sarfe.case.plausibility.SPAN_RANGE_M` is
taken for a unit mistake (mm read as m, or the reverse) and refused.
"""
from __future__ import annotations

import importlib

import numpy as np

from sarfe.case.messages import suggestion
from sarfe.case.plausibility import SPAN_RANGE_M
from sarfe.mesh import load_mesh
from sarfe.mesh.cache import cached_mesh
from sarfe.mesh.generators import GENERATORS, parameter_names


def generate_mesh(name, mesh_size, params):
    """sarfe.mesh.generators.<name>.generate(mesh_size=..., **params) → PanelMesh, through the
    checksummed mesh cache (sarfe.mesh.cache: generated once per parameter set)."""
    if name not in GENERATORS:
        importlib.import_module(f"sarfe.mesh.generators.{name}")  # ImportError names it
    return cached_mesh(name, mesh_size, **params)


def check_generator_params(case, generator) -> None:
    """An unknown key in model.fe.generator.params → CaseError naming it and the valid ones."""
    if generator.name not in GENERATORS:
        return
    valid = parameter_names(generator.name)
    for key in generator.params:
        if key not in valid:
            close = suggestion(key, valid)
            hint = f"did you mean '{close}'? " if close else ""
            raise case.error(f"unknown parameter of generator {generator.name} ({hint}valid: "
                             f"{', '.join(valid)})", ("model", "fe", "generator", "params", key))


def load_case_mesh(case):
    """The case's PanelMesh (file or generator), in metres; errors name model.fe.mesh/generator."""
    fe = case.config.model.fe
    if fe.source == "mesh":
        path = case.resolve(fe.mesh)
        try:
            mesh = load_mesh(path, length_unit=fe.mesh_units)
        except Exception as exc:
            raise case.error(f"cannot read mesh file {path}: {exc}", ("model", "fe", "mesh")) from None
        where = ("model", "fe", "mesh_units")
    else:
        gen = fe.generator
        check_generator_params(case, gen)
        try:
            mesh = generate_mesh(gen.name, gen.mesh_size_m, gen.params)
        except ImportError as exc:
            raise case.error(f"mesh generator '{gen.name}' is not available ({exc})",
                             ("model", "fe", "generator", "name")) from None
        except TypeError as exc:
            raise case.error(f"generator rejected a parameter: {exc}",
                             ("model", "fe", "generator", "params")) from None
        except ValueError as exc:
            raise case.error(str(exc), ("model", "fe", "generator")) from None
        where = ("model", "fe", "generator")
    if mesh.n_triangles == 0:
        raise case.error("the mesh has no shell triangles", where[:3])
    extent = float(np.linalg.norm(np.ptp(mesh.points, axis=0)))
    if extent > SPAN_RANGE_M[1]:
        raise case.error(f"the mesh spans {extent:.3g} m — are its coordinates in mm? "
                         "(set mesh_units: mm)", where)
    if extent < SPAN_RANGE_M[0]:
        raise case.error(f"the mesh spans only {extent:.3g} m — are its coordinates in metres "
                         "while mesh_units says mm?", where)
    return mesh


__all__ = ["load_case_mesh", "generate_mesh", "check_generator_params"]
