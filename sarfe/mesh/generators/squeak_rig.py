"""Squeak rig: a cantilever strip carrying a spherical-cap rubbing pad that rests on a clamped plate.

Geometry (mid-surfaces, metres; plate centred at the origin in the plane z = 0):

* plate  [-a/2, a/2]² at z = 0, clamped on all edges                 → `part_plate`, `skin`, `clamp_plate`
* beam   x ∈ [x_pad − L + inset, x_pad + inset], y ∈ y_pad ± b/2 at z = gap + h_cap,
  clamped at its left end                                           → `part_beam`, `clamp_beam`
* pad    spherical cap (sphere radius R, rim radius r, height h_cap = R − √(R² − r²)) welded
  conformally into a circular hole of the beam, apex pointing down  → `part_bump`
* `contact_rub_a` = cap apex (a mesh node), `contact_rub_b` = plate node straight below;
  |a − b| = gap (default 0: the pad touches the plate, the normal preload comes from the case).
* `excite_beam`: one beam node on the centre line at `excite_fraction`·L from the clamp.

Suggested properties: beam steel 1.5 mm, pad steel 1.5 mm, plate ABS or PP 2.5 mm.
"""
from __future__ import annotations

import math

from sarfe.mesh.gmsh_model import gmsh_session
from sarfe.mesh.mesh import PanelMesh
from sarfe.mesh.generators._gmsh import add_group, add_rig_clamps, embed_points, finish, refine_ball, set_mesh_size


def generate(mesh_size: float = 0.005, path=None, plate_size: float = 0.1,
             beam_length: float = 0.2, beam_width: float = 0.02, pad_x: float = 0.0,
             pad_y: float = 0.0, pad_inset: float = 0.012, pad_rim_radius: float = 0.006,
             pad_sphere_radius: float = 0.012, gap: float = 0.0,
             excite_fraction: float = 0.75) -> PanelMesh:
    """Mesh the squeak rig with target edge length `mesh_size` [m]; write `.msh` to `path` if given."""
    half = plate_size / 2
    r, R = pad_rim_radius, pad_sphere_radius
    if not (0 < r < R and r < beam_width / 2 and r < pad_inset and gap >= 0
            and abs(pad_x) + r < half and abs(pad_y) + r < half and 0 < excite_fraction < 1):
        raise ValueError("squeak_rig: need 0 < rim radius < sphere radius, pad inside beam and plate")
    cap_height = R - math.sqrt(R * R - r * r)
    z_beam = gap + cap_height
    x_free = pad_x + pad_inset
    x_clamp = x_free - beam_length
    if x_clamp + excite_fraction * beam_length > pad_x - r - mesh_size / 2:
        excite_fraction = 0.5 * (pad_x - r - x_clamp) / beam_length
    with gmsh_session() as gmsh:
        occ = gmsh.model.occ
        set_mesh_size(gmsh, mesh_size)
        refine_ball(gmsh, (pad_x, pad_y, z_beam), 1.5 * r, min(mesh_size, r / 3), mesh_size)
        plate = occ.addRectangle(-half, -half, 0.0, plate_size, plate_size)
        strip = occ.addRectangle(x_clamp, pad_y - beam_width / 2, z_beam, beam_length, beam_width)
        apex = occ.addPoint(pad_x, pad_y, gap)
        centre = occ.addPoint(pad_x, pad_y, gap + R)
        rim = occ.addPoint(pad_x + r, pad_y, z_beam)
        arc = occ.addCircleArc(apex, centre, rim)
        revolved = occ.revolve([(1, arc)], pad_x, pad_y, 0.0, 0.0, 0.0, 1.0, 2 * math.pi)
        cap = [t for d, t in revolved if d == 2]
        occ.remove([(0, centre)])
        # imprint the rim circle on the strip, drop the disk inside it
        out, out_map = occ.fragment([(2, strip)], [(2, t) for t in cap])
        occ.synchronize()
        strip_pieces = [t for d, t in out_map[0] if d == 2]
        inner = [t for t in strip_pieces if occ.getMass(2, t) < 2 * math.pi * r * r]
        beam = [t for t in strip_pieces if t not in inner]
        cap = [t for d, t in out if d == 2 and t not in strip_pieces]
        occ.remove([(2, t) for t in inner])
        occ.synchronize()
        apex_tag = [t for d, t in gmsh.model.getBoundary([(2, t) for t in cap], combined=False,
                                                         oriented=False, recursive=True)
                    if d == 0 and abs(gmsh.model.getValue(0, t, [])[2] - gap) < 1e-9]
        if len(beam) != 1 or len(apex_tag) != 1:
            raise RuntimeError("squeak_rig: welding the pad into the strip failed")
        (tip_b,) = embed_points(gmsh, plate, [(pad_x, pad_y, 0.0)])
        (excite,) = embed_points(gmsh, beam[0], [(x_clamp + excite_fraction * beam_length, pad_y, z_beam)])
        add_rig_clamps(gmsh, x_clamp, pad_y, z_beam, beam_width, plate)
        add_group(gmsh, 0, apex_tag, "contact_rub_a")
        add_group(gmsh, 0, tip_b, "contact_rub_b")
        add_group(gmsh, 0, excite, "excite_beam")
        add_group(gmsh, 2, plate, "skin")
        add_group(gmsh, 2, beam, "part_beam")
        add_group(gmsh, 2, cap, "part_bump")
        add_group(gmsh, 2, plate, "part_plate")
        return finish(gmsh, path)
