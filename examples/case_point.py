r"""One frequency point of a shipped FE case, by harmonic balance and by time integration: the
helper of examples 3–5.

The case goes through the public pipeline: ``load_case`` (YAML → checked case), ``build_linear_model``
(mesh → shell K, M → Craig–Bampton reduced model, contact rows G, ERP map N), ``nonlinear_model``
(damping D, contact set, force harmonics f̃). At Ω = 2π f the periodic response ũ (2H+1, n) of

    M ü + D u̇ + K u + Gᵀ λ(G u, G u̇) = f(t)

is solved twice, independently:

- harmonic balance (:func:`sarfe.hbm.solve_frequency`, the case's H and N, Hill stability off);
- Newmark time integration to the periodic steady state (:func:`sarfe.hbm.time_integration.
  integrate_time`, ``steps_per_period`` steps, started from the linear response), whose last period
  is analysed into the same H harmonics.

From each: the equivalent radiated power of the radiating surface, P = Σ_k ½ ρ c σ Σ_i A_i |ṽ_n,ik|²,
as an A-weighted level L_WA [dB(A) re 1 pW], and the first-harmonic normal amplitude
|ŵ₁| = √(a₁² + b₁²) [m] of each named contact (largest over its node pairs).
"""
from __future__ import annotations

import pathlib
from dataclasses import dataclass

import numpy as np

from sarfe.erp import equivalent_radiated_power
from sarfe.hbm import SolverOptions, solve_frequency
from sarfe.hbm.time_integration import integrate_time
from sarfe.pipeline import build_linear_model, load_case, nonlinear_model

CASES = pathlib.Path(__file__).resolve().parents[1] / "cases"


@dataclass(frozen=True)
class Point:
    """The two solutions' numbers at one frequency [Hz]; ``time_*`` None without time integration."""

    frequency_hz: float
    level_dba: float
    gap_amplitude_m: dict
    peak_normal_force_N: dict
    time_level_dba: float | None = None
    time_gap_amplitude_m: dict | None = None


def level_dba(case, stage, displacement, omega) -> float:
    """L_WA [dB(A) re the case's reference power] of displacement harmonics (2H+1, n) at ω."""
    erp = case.config.erp
    normal = np.asarray(displacement) @ np.asarray(stage.erp_map).T     # W = N ũ, (2H+1, n_s) [m]
    result = equivalent_radiated_power(normal, omega, stage.erp_areas, density=erp.rho_kg_m3,
                                       sound_speed=erp.c_m_s,
                                       radiation_loss_factor=erp.radiation_loss_factor,
                                       reference_power=erp.reference_power_W)
    return float(result.level_total_a_db)


def gap_amplitudes(nl, displacement) -> dict:
    """{contact: largest first-harmonic normal amplitude |G ũ₁| of its pairs [m]}."""
    U = np.asarray(displacement)
    out = {}
    for name, _, pairs in nl.groups:
        rows = nl.contacts.normal_row[pairs]
        rows = rows[rows >= 0]
        if rows.size:
            G = nl.contacts.gap_map[rows]
            out[name] = float(np.hypot(G @ U[1], G @ U[2]).max())
    return out


def peak_normal_forces(nl, solution) -> dict:
    """{contact: largest normal contact force over the period, summed over its pairs [N]}."""
    force = np.asarray(solution.contact_force_time)                    # (N, contact rows)
    out = {}
    for name, _, pairs in nl.groups:
        rows = nl.contacts.normal_row[pairs]
        rows = rows[rows >= 0]
        if rows.size:
            out[name] = float((force[:, rows].sum(axis=1) + nl.contacts.normal_load[pairs].sum()).max())
    return out


def solve_point(case_file: str, frequency_hz: float, steps_per_period: int | None = 512) -> Point:
    """Both solutions of ``cases/<case_file>`` at ``frequency_hz`` (module docstring);
    ``steps_per_period`` None: harmonic balance only."""
    case = load_case(CASES / case_file)
    stage = build_linear_model(case)
    nl = nonlinear_model(case, stage)
    H, N = case.config.solver.harmonics, case.config.solver.samples_per_period
    omega = 2 * np.pi * frequency_hz
    hbm = solve_frequency(nl.model, nl.contacts, nl.excitation, omega, H, N,
                          options=SolverOptions(stability=False))
    if not hbm.converged:
        raise RuntimeError(f"{case_file} at {frequency_hz} Hz: harmonic balance did not converge")
    point = dict(frequency_hz=frequency_hz, level_dba=level_dba(case, stage, hbm.displacement, omega),
                 gap_amplitude_m=gap_amplitudes(nl, hbm.displacement),
                 peak_normal_force_N=peak_normal_forces(nl, hbm))
    if steps_per_period is not None:
        time = integrate_time(nl.model, nl.contacts, nl.excitation, omega, H,
                              steps_per_period=steps_per_period)
        if not time.steady:
            raise RuntimeError(f"{case_file} at {frequency_hz} Hz: no periodic steady state reached")
        point.update(time_level_dba=level_dba(case, stage, time.displacement_harmonics, omega),
                     time_gap_amplitude_m=gap_amplitudes(nl, time.displacement_harmonics))
    return Point(**point)
