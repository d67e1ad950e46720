"""The two side-by-side problems in the peer HBM code pyHarm (pyharm-os 1.2.2), run in its own venv.

python pyharm_problems.py {example03|jenkins} [--step ds]  →  one JSON line on stdout:
{"problem", "points", "peak_amplitude", "peak_omega", "omega": [...], "amplitude": [...]}

amplitude = √(u_1c² + u_1s²) of the first harmonic of the reported DOF (example 03: DOF 1, the
forced mass, as NLvib plots it; Jenkins: the only DOF). Written from pyHarm's public input format
(Maestro dict: analysis / system / substructures / connectors), see its tutorials. The arc-length
step: ds0 = ds_max = ``--step`` (0.04 gives 187 points on example 03).
"""
import argparse
import json

import numpy as np
from pyHarm.Maestro import Maestro


def example03(step):
    """NLvib example 03: M = I, K = [[1, −1], [−1, 2]], D = 0.03 K, F = 0.1 cos Ωt on DOF 1,
    unilateral spring k = 100, gap 1 on DOF 0 against ground; H = 21, N = 1024, Ω 0.8 → 0.5."""
    K = np.array([[1.0, -1.0], [-1.0, 2.0]])
    matrices = {"M": np.eye(2), "C": 0.03 * K, "K": K, "G": np.zeros((2, 2))}
    data = {
        "analysis": {"FRF": {"study": "frf", "puls_inf": 0.5, "puls_sup": 0.8, "puls_start": 0.8,
                             "sign_ds": -1, "ds0": step, "ds_min": 1e-8, "ds_max": step,
                             "verbose": False, "stepsizer": "acceptance", "predictor": "tangent",
                             "corrector": "arc_length", "stopper": "bounds",
                             "solver": "scipyroot"}},
        "system": {"type": "Base", "nh": 21, "nti": 1024},
        "substructures": {"sub1": {"matrix": matrices, "ndofs": 1}},
        "connectors": {
            "loading": {"type": "CosinusForcing", "connect": {"sub1": [1]}, "dirs": [0], "amp": 0.1},
            "stop": {"type": "PenaltyUnilateralGap", "connect": {"sub1": [0]}, "dirs": [0],
                     "g": 1.0, "k": 100.0},
        },
    }
    return data, 1


def jenkins(step):
    """1-DOF Jenkins oscillator: m = k = k_t = μ = N0 = 1, c = 0.02, F = 0.5 cos Ωt;
    H = 7, N = 256, Ω 0.5 → 2.0."""
    matrices = {"M": np.eye(1), "C": 0.02 * np.eye(1), "K": np.eye(1), "G": np.zeros((1, 1))}
    data = {
        "analysis": {"FRF": {"study": "frf", "puls_inf": 0.5, "puls_sup": 2.0, "puls_start": 0.5,
                             "sign_ds": 1, "ds0": step, "ds_min": 1e-8, "ds_max": step,
                             "verbose": False, "stepsizer": "acceptance", "predictor": "tangent",
                             "corrector": "arc_length", "stopper": "bounds",
                             "solver": "scipyroot"}},
        "system": {"type": "Base", "nh": 7, "nti": 256},
        "substructures": {"sub1": {"matrix": matrices, "ndofs": 1}},
        "connectors": {
            "loading": {"type": "CosinusForcing", "connect": {"sub1": [0]}, "dirs": [0], "amp": 0.5},
            "friction": {"type": "Jenkins", "connect": {"sub1": [0]}, "dirs": [0],
                         "mu": 1.0, "N0": 1.0, "k": 1.0},
        },
    }
    return data, 0


def main(name, step):
    data, node = {"example03": example03, "jenkins": jenkins}[name](step)
    maestro = Maestro(data)
    maestro.operate()
    dofs = maestro.system.expl_dofs
    rows = dofs[(dofs["sub"] == "sub1") & (dofs["node_num"] == node) & (dofs["dof_num"] == 0)
                & (dofs["harm"] == 1)].index.to_numpy()
    accepted = [s for s in maestro.nls["FRF"].SolList if s.flag_accepted]
    omega = np.array([s.x[-1] for s in accepted])
    amplitude = np.array([np.linalg.norm(s.x[rows]) for s in accepted])
    peak = int(amplitude.argmax())
    print(json.dumps({"problem": name, "points": len(accepted),
                      "peak_amplitude": float(amplitude[peak]), "peak_omega": float(omega[peak]),
                      "omega": omega.tolist(), "amplitude": amplitude.tolist()}))


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("problem", choices=["example03", "jenkins"])
    parser.add_argument("--step", type=float, default=0.04, help="arc-length step ds (ds0 = ds_max)")
    args = parser.parse_args()
    main(args.problem, args.step)
