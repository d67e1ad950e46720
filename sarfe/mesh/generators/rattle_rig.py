"""Rattle rig: a steel cantilever strip whose tip striker hovers just above a clamped ABS plate.

Geometry (mid-surfaces, metres; plate centred at the origin in the plane z = 0):

* plate  [-a/2, a/2]² at z = 0, clamped on all four edges            → `part_plate`, `skin`, `clamp_plate`
* beam   x ∈ [x_tip − L, x_tip], y ∈ y_tip ± b/2 at z = gap, clamped at x = x_tip − L → `part_beam`, `clamp_beam`
* striker: node `contact_tip_a` on the beam centre line `striker_inset` before the free end,
  node `contact_tip_b` on the plate straight below; |a − b| = gap (the striker is rigid and its
  length together with the half thicknesses is absorbed in the geometric gap)
* `excite_beam`: one beam node on the centre line at `excite_fraction`·L from the clamp.

Suggested properties (for the case file): beam steel 1.5 mm, plate ABS 2.5 mm.
"""
from __future__ import annotations

from sarfe.mesh.gmsh_model import gmsh_session
from sarfe.mesh.mesh import PanelMesh
from sarfe.mesh.generators._gmsh import add_group, add_rig_clamps, embed_points, finish, set_mesh_size

DEFAULTS = dict(plate_size=0.15, beam_length=0.2, beam_width=0.02, gap=0.5e-3,
                tip_x=0.03, tip_y=0.02, striker_inset=0.005, excite_fraction=0.75)


def generate(mesh_size: float = 0.005, path=None, plate_size: float = 0.15,
             beam_length: float = 0.2, beam_width: float = 0.02, gap: float = 0.5e-3,
             tip_x: float = 0.03, tip_y: float = 0.02, striker_inset: float = 0.005,
             excite_fraction: float = 0.75) -> PanelMesh:
    """Mesh the rattle rig with target edge length `mesh_size` [m]; write `.msh` to `path` if given."""
    half = plate_size / 2
    if not (gap > 0 and abs(tip_x) < half and abs(tip_y) + beam_width / 2 < half
            and 0 < striker_inset < beam_length and 0 < excite_fraction < 1):
        raise ValueError("rattle_rig: striker must lie over the plate, gap > 0, 0 < excite_fraction < 1")
    x_clamp = tip_x - beam_length
    with gmsh_session() as gmsh:
        occ = gmsh.model.occ
        set_mesh_size(gmsh, mesh_size)
        plate = occ.addRectangle(-half, -half, 0.0, plate_size, plate_size)
        beam = occ.addRectangle(x_clamp, tip_y - beam_width / 2, gap, beam_length, beam_width)
        occ.synchronize()
        striker = (tip_x - striker_inset, tip_y)
        (tip_a,) = embed_points(gmsh, beam, [(*striker, gap)])
        (tip_b,) = embed_points(gmsh, plate, [(*striker, 0.0)])
        (excite,) = embed_points(gmsh, beam, [(x_clamp + excite_fraction * beam_length, tip_y, gap)])
        add_rig_clamps(gmsh, x_clamp, tip_y, gap, beam_width, plate)
        add_group(gmsh, 0, tip_a, "contact_tip_a")
        add_group(gmsh, 0, tip_b, "contact_tip_b")
        add_group(gmsh, 0, excite, "excite_beam")
        add_group(gmsh, 2, plate, "skin")
        add_group(gmsh, 2, beam, "part_beam")
        add_group(gmsh, 2, plate, "part_plate")
        return finish(gmsh, path)
