"""Instrument panel top: doubly curved carrier with ribs and clip towers, plus a decor trim strip.

Carrier (plan view x ∈ [0, L] across the car, y ∈ [0, W] fore-aft, default 1.2 m × 0.4 m;
outer skin faces +z):  f(x, y) = crown_x (1 − ξ²) + crown_y (1 − η²),  ξ = 2x/L − 1, η = y/W
(highest at the driver-side edge y = 0, falling towards the windscreen y = W).
Ribs: 5 across (along y) and 2 lengthwise (along x), 20 mm deep; 10 clip towers → `clip_1..10`.
Trim strip (`part_trim_strip`, 0.6 m × 0.1 m): flange 0.5 mm in front of the skin, 8 mm crown,
fixed by `clip_strip_1..4`, touching the carrier at `contact_<spot>_a/_b` for spots
`front_1`, `front_2`, `rear_1` (suggested rattle) and `end_left`, `end_right` (suggested squeak).
Excitation nodes: `excite_carrier`, `excite_strip`.  Element groups: `skin` = `part_carrier`,
`part_ribs`, `part_bosses`, `part_trim_strip`.  Suggested thicknesses: carrier 3 mm, ribs 2 mm,
bosses 2 mm, strip 2 mm.

Bodies: carrier + ribs + bosses one conformal component, the strip another; they interact only
through the contact pairs.
"""
from __future__ import annotations

from sarfe.mesh.mesh import PanelMesh
from sarfe.mesh.generators._panel import AttachedPart, PanelSpec, build


def spec(length: float = 1.2, width: float = 0.4, crown_x: float = 0.04, crown_y: float = 0.05,
         rib_height: float = 0.02, gap: float = 0.5e-3, strip_depth: float = 0.008) -> PanelSpec:
    """Geometry of the instrument panel; positions scale with `length` and `width`."""

    def height(x, y):
        xi, eta = 2 * x / length - 1, y / width
        return crown_x * (1 - xi ** 2) + crown_y * (1 - eta ** 2)

    sx, sy = length / 1.2, width / 0.4
    s = lambda pts: {k: (x * sx, y * sy) for k, (x, y) in pts.items()}  # noqa: E731
    strip = AttachedPart(
        name="trim_strip", x0=0.30 * sx, x1=0.90 * sx, y0=0.14 * sy, y1=0.24 * sy,
        depth=strip_depth, flange=0.015, ramp=0.015, gap=gap,
        contacts=s({"front_1": (0.45, 0.1475), "front_2": (0.75, 0.1475), "rear_1": (0.52, 0.2325),
                    "end_left": (0.3075, 0.19), "end_right": (0.8925, 0.19)}),
        clips=s({"clip_strip_1": (0.3075, 0.1475), "clip_strip_2": (0.8925, 0.1475),
                 "clip_strip_3": (0.3075, 0.2325), "clip_strip_4": (0.8925, 0.2325)}),
        excite=s({"excite_strip": (0.6, 0.19)}),
    )
    clips = tuple((x * sx, 0.04 * sy) for x in (0.05, 0.25, 0.48, 0.72, 0.95, 1.15)) + \
        tuple((x * sx, 0.36 * sy) for x in (0.25, 0.48, 0.72, 0.95))
    return PanelSpec(
        length=length, width=width, height=height,
        ribs_along_x=tuple(y * sy for y in (0.12, 0.28)),
        ribs_along_y=tuple(x * sx for x in (0.15, 0.35, 0.60, 0.85, 1.05)),
        rib_height=rib_height, rib_margin=0.03, clips=clips, boss_radius=0.006, boss_height=0.02,
        attached=strip, excite=s({"excite_carrier": (0.5, 0.32)}),
    )


def generate(mesh_size: float = 0.01, path=None, **params) -> PanelMesh:
    """Mesh the instrument panel with target edge length `mesh_size` [m]; parameters of `spec`."""
    return build(spec(**params), mesh_size, path)
