"""Stand-in for sarfe.pipeline with the same contract, for batch tests only.

One mass on a spring hitting a stop at ``gap_m``: |x| = F/|k - m w^2 + i c w|, the contact rattles
when |x| > gap. ``BATCH_FAKE_LOG`` (a file) gets one line per call of build/solve, so that calls in
Dask worker processes can be counted.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import time
from dataclasses import dataclass

from sarfe.case.errors import CaseError


@dataclass(frozen=True)
class Case:
    data: dict


@dataclass(frozen=True)
class LinearStage:
    key: str
    mass: float
    stiffness: float
    damping: float


@dataclass
class CaseResult:
    summary: dict
    rows: list
    exit_code: int


def _log(what: str) -> None:
    path = os.environ.get("BATCH_FAKE_LOG")
    if path:
        with open(path, "a") as stream:
            stream.write(f"{what} {os.getpid()}\n")


def load_case(data, base_dir=None) -> Case:
    if not isinstance(data, dict):
        raise CaseError("fake pipeline takes mappings only")
    for index, contact in enumerate(data.get("contacts", [])):
        if contact["gap_m"] < 0:
            raise CaseError(f"contacts[{index}].gap_m: must be >= 0, got {contact['gap_m']}")
    return Case(data)


def linear_model_key(case: Case) -> str:
    return hashlib.sha256(json.dumps(case.data["model"], sort_keys=True).encode()).hexdigest()[:16]


def build_linear_model(case: Case, progress=False) -> LinearStage:
    _log("build")
    time.sleep(case.data.get("build_sleep_s", 0.0))
    model = case.data["model"]
    mass, stiffness = model["mass_kg"], model["stiffness_N_m"]
    return LinearStage(linear_model_key(case), mass, stiffness, 2 * model["damping_ratio"] * math.sqrt(stiffness * mass))


def solve_case(case: Case, linear_stage=None, output_dir=None, progress=False, write=True) -> CaseResult:
    _log("solve")
    data = case.data
    if linear_stage is None:
        linear_stage = build_linear_model(case)
    time.sleep(data.get("sleep_s", 0.0))
    if data.get("die_once") and not os.path.exists(data["die_once"]):
        open(data["die_once"], "w").close()
        os._exit(1)  # a worker dying mid-variant
    if data.get("fail"):
        raise RuntimeError(data["fail"])
    force = data["excitation"]["force_N"]
    freq = data["frequency"]
    rows = []
    for k in range(freq["points"]):
        hz = freq["start_hz"] + k * (freq["stop_hz"] - freq["start_hz"]) / max(freq["points"] - 1, 1)
        omega = 2 * math.pi * hz
        amplitude = force / abs(complex(linear_stage.stiffness - linear_stage.mass * omega**2, linear_stage.damping * omega))
        velocity = amplitude * omega
        row = {"frequency_hz": hz, "converged": not data.get("nonconverged", False), "stable": True,
               "erp_db": 20 * math.log10(velocity / 1e-9), "erp_dba": 20 * math.log10(velocity / 1e-9) - 5.0}
        for contact in data.get("contacts", []):
            penetration = max(amplitude - contact["gap_m"], 0.0)
            row[f"{contact['name']}.max_penetration_m"] = penetration
            row[f"{contact['name']}.peak_normal_force_N"] = contact["normal_stiffness_N_m"] * penetration
        impact = sum(v for k, v in row.items() if k.endswith(".peak_normal_force_N"))
        row["erp_db"] += 10 * math.log10(1.0 + impact)
        rows.append(row)
    if write and output_dir is not None:
        os.makedirs(output_dir, exist_ok=True)
        with open(os.path.join(output_dir, "summary.json"), "w") as stream:
            json.dump({"points": len(rows)}, stream)
    converged = all(r["converged"] for r in rows)
    return CaseResult(summary={"all_converged": converged, "max_erp_db": max(r["erp_db"] for r in rows)},
                      rows=rows, exit_code=0 if converged else 3)
