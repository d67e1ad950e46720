"""Door trim panel: doubly curved carrier skin with ribs and clip bosses, plus a map pocket.

Carrier (plan view x ∈ [0, L], y ∈ [0, W], default L = 0.9 m, W = 0.55 m; outer skin faces +z):
    f(x, y) = crown_x (1 − ξ²) + crown_y (1 − η²) + twist ξ η,   ξ = 2x/L − 1, η = 2y/W − 1
Ribs (3 along x, 4 along y, 15 mm deep) and 10 clip bosses (Ø 12 mm, 20 mm deep) behind the
skin; `clip_1..clip_10` are the rim nodes at the far end of each boss.
Map pocket (`part_map_pocket`): flange 0.5 mm in front of the skin, 40 mm deep bulge, fixed by
`clip_pocket_1..4`, touching the carrier at six spots (`contact_<spot>_a` on the pocket,
`contact_<spot>_b` on the skin, |a − b| = gap along the skin normal):
`lower_1..3`, `upper_1` (suggested rattle spots) and `side_left`, `side_right` (squeak spots).
More spots for bigger studies: `rattle_spots` (4 … 12) on the lower and upper flanges —
`upper_2`, `upper_3`, `lower_4`, `lower_5`, `upper_4`, `upper_5`, `lower_6`, `upper_6` in that
order — and `squeak_spots` (2, 4 or 6) on the side flanges — `side_left_2`, `side_right_2`,
`side_left_3`, `side_right_3`; the defaults (4, 2) give the six spots above.
Excitation nodes: `excite_carrier` (skin), `excite_pocket` (pocket bulge).
Element groups: `skin` = `part_carrier`, `part_ribs`, `part_bosses`, `part_map_pocket`.
Suggested thicknesses: carrier 2.5 mm, ribs 1.5 mm, bosses 2 mm, pocket 2 mm (PP / ABS).

Bodies: carrier + ribs + bosses are one conformal mesh component, the pocket another; they
interact only through the contact pairs.  Node count ≈ 29k at 5 mm, ≈ 7.5k at 10 mm.
"""
from __future__ import annotations

from sarfe.mesh.mesh import PanelMesh
from sarfe.mesh.generators._panel import AttachedPart, PanelSpec, build


# contact spots on the pocket flange in the unscaled plan (1.0 × 0.6 m; scaled by length, width),
# in the order they are added: the first 4 rattle / 2 squeak spots are the shipped demo's.  Every
# spot stays ≥ 18 mm from the ribs (x = 0.18, 0.42, 0.66, 0.88; y = 0.12, 0.30, 0.48), ≥ 20 mm
# from the pocket clips (corners of the flange mid-line) and ≥ 40 mm from every other spot.
RATTLE_SPOTS = (("lower_1", (0.32, 0.1725)), ("lower_2", (0.54, 0.1725)),
                ("lower_3", (0.74, 0.1725)), ("upper_1", (0.53, 0.3875)),
                ("upper_2", (0.33, 0.3875)), ("upper_3", (0.73, 0.3875)),
                ("lower_4", (0.44, 0.1725)), ("lower_5", (0.63, 0.1725)),
                ("upper_4", (0.45, 0.3875)), ("upper_5", (0.61, 0.3875)),
                ("lower_6", (0.37, 0.1725)), ("upper_6", (0.38, 0.3875)))
SQUEAK_SPOTS = (("side_left", (0.2625, 0.33)), ("side_right", (0.7875, 0.33)),
                ("side_left_2", (0.2625, 0.22)), ("side_right_2", (0.7875, 0.22)),
                ("side_left_3", (0.2625, 0.265)), ("side_right_3", (0.7875, 0.265)))


def contact_spots(rattle_spots: int = 4, squeak_spots: int = 2) -> dict:
    """{spot name: (x, y)} in the unscaled plan: the first `rattle_spots` of RATTLE_SPOTS and
    the first `squeak_spots` of SQUEAK_SPOTS (the names are suggestions: the case picks the law)."""
    for name, count, table, low in (("rattle_spots", rattle_spots, RATTLE_SPOTS, 0),
                                    ("squeak_spots", squeak_spots, SQUEAK_SPOTS, 0)):
        if not isinstance(count, int) or isinstance(count, bool) or not low <= count <= len(table):
            raise ValueError(f"{name} = {count!r}: must be an integer from {low} to {len(table)}")
    if rattle_spots + squeak_spots == 0:
        raise ValueError("rattle_spots + squeak_spots = 0: the map pocket needs a contact spot")
    # order of the shipped demo: lower_1..3, upper_1, side_left, side_right, then the extras
    spots = dict(RATTLE_SPOTS[:min(rattle_spots, 4)]) | dict(SQUEAK_SPOTS[:min(squeak_spots, 2)])
    return spots | dict(RATTLE_SPOTS[4:rattle_spots]) | dict(SQUEAK_SPOTS[2:squeak_spots])


def spec(length: float = 0.9, width: float = 0.55, crown_x: float = 0.03, crown_y: float = 0.015,
         twist: float = 0.01, rib_height: float = 0.015, gap: float = 0.5e-3,
         pocket_depth: float = 0.04, rattle_spots: int = 4, squeak_spots: int = 2) -> PanelSpec:
    """Geometry of the door trim; positions scale with `length` and `width`; `rattle_spots`,
    `squeak_spots`: how many contact spots of each table (module docstring)."""

    def height(x, y):
        xi, eta = 2 * x / length - 1, 2 * y / width - 1
        return crown_x * (1 - xi ** 2) + crown_y * (1 - eta ** 2) + twist * xi * eta

    sx, sy = length / 1.0, width / 0.6
    s = lambda pts: {k: (x * sx, y * sy) for k, (x, y) in pts.items()}  # noqa: E731
    pocket = AttachedPart(
        name="map_pocket", x0=0.25 * sx, x1=0.80 * sx, y0=0.16 * sy, y1=0.40 * sy,
        depth=pocket_depth, flange=0.025, ramp=0.04, gap=gap,
        contacts=s(contact_spots(rattle_spots, squeak_spots)),
        clips=s({"clip_pocket_1": (0.2625, 0.1725), "clip_pocket_2": (0.7875, 0.1725),
                 "clip_pocket_3": (0.2625, 0.3875), "clip_pocket_4": (0.7875, 0.3875)}),
        excite=s({"excite_pocket": (0.525, 0.28)}),
    )
    clips = tuple((x * sx, y * sy) for y in (0.05, 0.55) for x in (0.1, 0.3, 0.55, 0.77, 0.95))
    return PanelSpec(
        length=length, width=width, height=height,
        ribs_along_x=tuple(y * sy for y in (0.12, 0.30, 0.48)),
        ribs_along_y=tuple(x * sx for x in (0.18, 0.42, 0.66, 0.88)),
        rib_height=rib_height, rib_margin=0.03, clips=clips, boss_radius=0.006, boss_height=0.02,
        attached=pocket, excite=s({"excite_carrier": (0.5, 0.52)}),
    )


def generate(mesh_size: float = 0.01, path=None, **params) -> PanelMesh:
    """Mesh the door trim with target edge length `mesh_size` [m]; parameters of `spec`."""
    return build(spec(**params), mesh_size, path)
