"""The lumped panel of cases/lumped_rattle.yaml with its seal coupled to the panel: the model of the
onset and sensitivity tests.

    DOF 0 panel normal (0.2 kg, 2e4 N/m), DOF 1 bracket (0.5 kg, 2e5 N/m), DOF 2 panel in plane
    (0.2 kg, 5e4 N/m), modal ζ = 0.03 — as the case, plus a coupling K_02 = −2e3 N/m so that the
    seal's friction shows in the radiating panel DOF (in the case the two are decoupled and
    dL_A/dμ = 0).
    rattle panel–bracket: w = u0 − u1, gap 0.1 mm, k_n = 1e6 N/m;
    squeak seal on DOF 2 against ground: N0 = 1 N, k_t = 1e5 N/m, μ = 0.4 (no normal DOF);
    base acceleration 3 m/s², influence (1, 0.2, 0.3); ERP of DOF 0 over 0.06 m².
"""
import numpy as np
import scipy.sparse as sp

from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.model import make_linear_model
from sarfe.fe.damping import modal_damping as reduced_modal_damping

MASS = np.diag([0.2, 0.5, 0.2])
STIFFNESS = np.array([[2.0e4, 0.0, -2.0e3], [0.0, 2.0e5, 0.0], [-2.0e3, 0.0, 5.0e4]])
ERP_MAP = np.array([[1.0, 0.0, 0.0]])
ERP_AREAS = np.array([0.06])
NOMINAL = {"gap": 1e-4, "normal_stiffness": 1e6, "tangential_stiffness": 1e5,
           "friction_coefficient": 0.4, "normal_load": 1.0}
RATTLE, SEAL = 0, 1


def model():
    return make_linear_model(MASS, reduced_modal_damping(MASS, STIFFNESS, 0.03), STIFFNESS)


def contacts(**changed):
    """The two contacts with the NOMINAL parameters, ``changed`` replacing some."""
    p = {**NOMINAL, **changed}
    G = sp.csr_matrix([[1.0, -1.0, 0.0], [0.0, 0.0, 1.0]])
    return make_contact_set(G, ["rattle", "squeak"], [0, -1], [[-1, -1], [1, -1]],
                            gap=[p["gap"], 0.0], parameters={
                                "normal_stiffness": [p["normal_stiffness"], 0.0],
                                "tangential_stiffness": [0.0, p["tangential_stiffness"]],
                                "friction_coefficient": [0.0, p["friction_coefficient"]],
                                "normal_load": [0.0, p["normal_load"]]})


def excitation(harmonics, level=1.0):
    """f̃_e (2H+1, 3) [N]: the base acceleration 3 m/s² × ``level`` as a cosine force M b a."""
    F = np.zeros((2 * harmonics + 1, 3))
    F[1] = level * 3.0 * np.diag(MASS) * np.array([1.0, 0.2, 0.3])
    return F
