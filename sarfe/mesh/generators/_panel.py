"""Shared builder of the trim-panel generators (door trim, instrument panel).

A carrier = doubly curved B-spline skin z = f(x, y) (mid-surface, outer side +z), with
ribs (vertical strips of height `rib_height` behind the skin, normal to the mean skin plane)
and clip bosses (vertical tubes behind the skin whose far rims are the `clip_<i>` supports),
all made conformal with the skin by OpenCASCADE fragmentation.  An attached part (map pocket,
trim strip) is a second B-spline surface in front of the skin: a flange band following
f + gap and a bulge of `depth` inside it.  Contact spots are node pairs: b on the skin
(exact surface point), a = b + gap·n (n the skin's unit normal), embedded in the attached part.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from sarfe.mesh.gmsh_model import gmsh_session
from sarfe.mesh.mesh import PanelMesh
from sarfe.mesh.generators._gmsh import add_group, finish, set_mesh_size

_LIFT = 3e-3  # rib/boss strips start this far in front of the skin, the sliver is cut away


@dataclass(frozen=True)
class AttachedPart:
    """Second part in front of the carrier, rectangle [x0, x1] × [y0, y1] in plan view [m]."""

    name: str
    x0: float
    x1: float
    y0: float
    y1: float
    depth: float              # bulge height in front of the flange [m]
    flange: float             # flange band width, follows the skin at `gap` [m]
    ramp: float               # width of the smooth rise from flange to bulge [m]
    gap: float                # normal distance flange ↔ skin mid-surfaces at contact spots [m]
    contacts: dict            # {pair name: (x, y)} spots on the flange
    clips: dict               # {group name: (x, y)} fixed nodes of the attached part
    excite: dict = field(default_factory=dict)   # {group name: (x, y)}


@dataclass(frozen=True)
class PanelSpec:
    length: float             # x extent [m]
    width: float              # y extent [m]
    height: object            # f(x, y) → z [m], vectorized
    ribs_along_x: tuple       # y positions of ribs running in x
    ribs_along_y: tuple       # x positions of ribs running in y
    rib_height: float
    rib_margin: float         # rib ends stay this far from the skin edge
    clips: tuple              # ((x, y), ...) boss centres → clip_1, clip_2, ...
    boss_radius: float
    boss_height: float
    attached: AttachedPart
    excite: dict              # {group name: (x, y)} points on the carrier skin
    control_spacing: float = 0.04   # B-spline control-point spacing [m]


def _bspline_surface(occ, x0, x1, y0, y1, z_of, spacing):
    nu = max(4, int(np.ceil((x1 - x0) / spacing)) + 1)
    nv = max(4, int(np.ceil((y1 - y0) / spacing)) + 1)
    X, Y = np.meshgrid(np.linspace(x0, x1, nu), np.linspace(y0, y1, nv))  # rows: v, columns: u
    Z = z_of(X, Y)
    points = [occ.addPoint(x, y, z) for x, y, z in zip(X.ravel(), Y.ravel(), Z.ravel())]
    surface = occ.addBSplineSurface(points, nu, degreeU=3, degreeV=3)
    occ.remove([(0, p) for p in points])
    return surface


def _smoothstep(t):
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3 - 2 * t)


def _check_clearance(spec: PanelSpec, points: dict, minimum: float):
    """Spots must stay off rib lines and boss rims so they are interior skin nodes."""
    for name, (x, y) in points.items():
        d = min([abs(y - r) for r in spec.ribs_along_x] + [abs(x - r) for r in spec.ribs_along_y]
                + [abs(np.hypot(x - cx, y - cy) - spec.boss_radius) for cx, cy in spec.clips])
        if d < minimum:
            raise ValueError(f"{name} at ({x}, {y}) is {d * 1e3:.1f} mm from a rib or boss; "
                             f"need {minimum * 1e3:.1f} mm")


def build(spec: PanelSpec, mesh_size: float, path=None) -> PanelMesh:
    """Mesh carrier + attached part of `spec` with target edge length `mesh_size` [m]."""
    part = spec.attached
    f = spec.height
    carrier_points = {f"contact_{k}_b": v for k, v in part.contacts.items()} | dict(spec.excite)
    _check_clearance(spec, carrier_points, 2e-3)
    for i, (cx, cy) in enumerate(spec.clips, start=1):
        d = min([abs(cy - r) for r in spec.ribs_along_x] + [abs(cx - r) for r in spec.ribs_along_y])
        if d < spec.boss_radius + 5e-3:
            raise ValueError(f"clip_{i} boss at ({cx}, {cy}) is {d * 1e3:.1f} mm from a rib")
    with gmsh_session() as gmsh:
        occ = gmsh.model.occ
        set_mesh_size(gmsh, mesh_size)
        skin = _bspline_surface(occ, 0.0, spec.length, 0.0, spec.width, f, spec.control_spacing)
        occ.synchronize()

        # exact skin points and normals for contact spots and excitation
        spots = {}
        for name, (x, y) in carrier_points.items():
            xyz, uv = gmsh.model.getClosestPoint(2, skin, [x, y, float(f(x, y))])
            normal = np.asarray(gmsh.model.getNormal(skin, uv))
            spots[name] = (np.asarray(xyz), normal * np.sign(normal[2]))
        point_tags = {name: occ.addPoint(*xyz) for name, (xyz, _) in spots.items()}

        # ribs and bosses: vertical strips from just in front of the skin to rib height behind
        tools = []
        m = spec.rib_margin
        for y in spec.ribs_along_x:
            xs = np.linspace(m, spec.length - m, 24)
            tools.append(_strip(occ, xs, np.full_like(xs, y), f, spec.rib_height))
        for x in spec.ribs_along_y:
            ys = np.linspace(m, spec.width - m, 16)
            tools.append(_strip(occ, np.full_like(ys, x), ys, f, spec.rib_height))
        bosses = [_boss(occ, cx, cy, spec.boss_radius, f, spec.boss_height) for cx, cy in spec.clips]
        n_ribs = len(tools)
        tools += [t for b in bosses for t in b]
        out, out_map = occ.fragment([(2, skin)], [(2, t) for t in tools] +
                                    [(0, t) for t in point_tags.values()])
        skin_faces = [t for d, t in out_map[0] if d == 2]
        rib_faces, boss_faces, slivers = [], [], []
        for i in range(len(tools)):
            for d, t in out_map[1 + i]:
                if d != 2 or t in skin_faces:
                    continue
                cx, cy, cz = occ.getCenterOfMass(2, t)
                if cz > f(cx, cy):
                    slivers.append(t)
                elif i < n_ribs:
                    rib_faces.append(t)
                else:
                    boss_faces.append(t)
        point_tags = {name: [t for d, t in out_map[1 + len(tools) + k] if d == 0]
                      for k, name in enumerate(point_tags)}
        rib_faces = sorted(set(rib_faces) - set(slivers))
        boss_faces = sorted(set(boss_faces) - set(slivers))
        occ.remove([(2, t) for t in sorted(set(slivers))], recursive=True)

        # attached part: flange at f + gap, smooth bulge of `depth` inside
        def z_part(x, y):
            inset = np.minimum(np.minimum(x - part.x0, part.x1 - x), np.minimum(y - part.y0, part.y1 - y))
            return f(x, y) + part.gap + part.depth * _smoothstep((inset - part.flange) / part.ramp)

        pocket = _bspline_surface(occ, part.x0, part.x1, part.y0, part.y1, z_part,
                                  min(spec.control_spacing, part.ramp / 2))
        occ.synchronize()
        pocket_points = {}
        for pair in part.contacts:
            xyz, normal = spots[f"contact_{pair}_b"]
            pocket_points[f"contact_{pair}_a"] = xyz + part.gap * normal
        for name, (x, y) in (part.clips | part.excite).items():
            pocket_points[name] = gmsh.model.getClosestPoint(2, pocket, [x, y, float(z_part(x, y))])[0]
        pocket_tags = {n: occ.addPoint(*map(float, p)) for n, p in pocket_points.items()}
        occ.synchronize()
        gmsh.model.mesh.embed(0, list(pocket_tags.values()), 2, pocket)

        # groups
        for i, (cx, cy) in enumerate(spec.clips, start=1):
            z = float(f(cx, cy)) - spec.boss_height
            r = spec.boss_radius + 1e-5
            rim = gmsh.model.getEntitiesInBoundingBox(cx - r, cy - r, z - 1e-5, cx + r, cy + r, z + 1e-5, 1)
            add_group(gmsh, 1, [t for _, t in rim], f"clip_{i}")
        for name, tags in point_tags.items():
            if len(tags) != 1:
                raise RuntimeError(f"{name}: fragment did not keep the point on the skin")
            add_group(gmsh, 0, tags, name)
        for name, tag in pocket_tags.items():
            add_group(gmsh, 0, [tag], name)
        add_group(gmsh, 2, skin_faces, "skin")
        add_group(gmsh, 2, skin_faces, "part_carrier")
        if rib_faces:
            add_group(gmsh, 2, rib_faces, "part_ribs")
        if boss_faces:
            add_group(gmsh, 2, boss_faces, "part_bosses")
        add_group(gmsh, 2, [pocket], f"part_{part.name}")
        return finish(gmsh, path)


def _strip(occ, xs, ys, f, depth):
    """Planar vertical rib face over the straight plan-view line (xs, ys).

    Top edge: spline through (x, y, f + `_LIFT`) (the sliver in front of the skin is cut away
    after fragmentation); bottom edge: spline through (x, y, f − depth).  All points lie in one
    vertical plane, so both splines and the face are planar.
    """
    top = [occ.addPoint(x, y, float(f(x, y)) + _LIFT) for x, y in zip(xs, ys)]
    bottom = [occ.addPoint(x, y, float(f(x, y)) - depth) for x, y in zip(xs, ys)]
    curves = [occ.addSpline(top), occ.addLine(top[-1], bottom[-1]),
              occ.addSpline(bottom[::-1]), occ.addLine(bottom[0], top[0])]
    return occ.addPlaneSurface([occ.addCurveLoop(curves)])


def _boss(occ, cx, cy, radius, f, depth, sides=8):
    """Octagonal clip tower: planar walls from above the skin to a flat rim `depth` behind it."""
    angles = np.linspace(0, 2 * np.pi, sides, endpoint=False) + np.pi / sides
    xs, ys = cx + radius * np.cos(angles), cy + radius * np.sin(angles)
    top = float(np.max(f(xs, ys))) + _LIFT
    bottom = float(f(cx, cy)) - depth
    points = [occ.addPoint(x, y, top) for x, y in zip(xs, ys)]
    lines = [occ.addLine(points[i], points[(i + 1) % sides]) for i in range(sides)]
    out = occ.extrude([(1, t) for t in lines], 0, 0, bottom - top)
    return [t for d, t in out if d == 2]
