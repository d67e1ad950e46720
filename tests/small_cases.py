"""Small case files for tests that run `sarfe` as a user does (shared by the tests): a 2-DOF
matrices case that solves in well under a second, and the rattle rig on its coarse 20 mm mesh
(123 nodes: a solve of a few points takes seconds)."""

TINY = """\
name: tiny
model:
  matrices:
    mass: [[1.0, 0.0], [0.0, 1.0]]
    stiffness: [[2.0e+4, -1.0e+4], [-1.0e+4, 2.0e+4]]
contacts:
  - {name: stop, type: rattle, normal_dof: 0, gap_m: 1.0e-3, normal_stiffness_N_m: 1.0e+5}
excitation:
  forces: [{dof: 0, force_N: 1.0}]
  frequency_hz: [20.0]
solver: {harmonics: 3, stability: false, error_estimate: false}
erp: {dofs: [0], areas_m2: [0.01]}
output: {files: [summary, table]}
"""


def tiny(mass: str = "[[1.0, 0.0], [0.0, 1.0]]", contact: str | None = None) -> str:
    """:data:`TINY` with another ``mass`` (e.g. a file name) and ``contact`` (a flow mapping)."""
    text = TINY.replace("mass: [[1.0, 0.0], [0.0, 1.0]]", f"mass: {mass}")
    if contact is not None:
        text = text.replace("{name: stop, type: rattle, normal_dof: 0, gap_m: 1.0e-3, "
                            "normal_stiffness_N_m: 1.0e+5}", contact)
    return text


def coarse_rig(frequencies_hz, solver: str, output: str = "") -> str:
    """cases/rattle_rig.yaml on a 20 mm mesh at ``frequencies_hz`` with the ``solver`` flow
    mapping (and an ``output`` line)."""
    return f"""\
name: coarse_rig
model:
  fe:
    generator: {{name: rattle_rig, mesh_size_m: 0.02, params: {{gap: 0.5e-3}}}}
    materials:
      part_plate: {{E_Pa: 2.2e9, nu: 0.37, rho_kg_m3: 1050}}
      part_beam:  {{E_Pa: 2.1e11, nu: 0.30, rho_kg_m3: 7850}}
    thickness_m: {{part_plate: 2.5e-3, part_beam: 1.5e-3}}
    fixed: [clamp_plate, clamp_beam]
damping: {{modal_zeta: 0.02}}
contacts:
  - {{name: tip, type: rattle, between: [contact_tip_a, contact_tip_b],
     gap_m: 0.5e-3, pairing_tolerance_m: 1.0e-3, normal_stiffness_N_m: 2.0e5,
     tolerance_m: 1.0e-4}}
excitation:
  forces: [{{group: excite_beam, direction: z, force_N: 0.05}}]
  frequency_hz: {list(frequencies_hz)}
solver: {solver}
erp: {{surface: skin}}
{output}
"""
