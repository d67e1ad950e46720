r"""The cost of a run, said before it is paid (issue 30 item 4): H, N, the reduction cutoff, an
estimated mode count, CPU seconds and bytes written — from what ``sarfe validate`` knows without
solving (the mesh or matrices, the contacts' node pairs, the case's options).

    model_size(...)  -> ModelSize      DOFs, nodes, triangles, radiating nodes, contact rows,
                                       the Weyl modal density of the shells [modes/Hz]
    run_cost(case, size) -> RunCost    points, H, N, cutoff, modes, CPU s (low, high), bytes
    cost_lines(cost) -> list           the validate/solve line(s), ≤ 80 columns each

**Modes.** The fixed-interface modes below the cutoff f_c, by the leading (Weyl) term of a thin
plate's eigenvalue count, summed over the triangles (area A_e, D_e = E t³ / (12 (1 − ν²))):

    N(f_c) ≈ Σ_e A_e k_e² / (4π),  k_e² = 2π f_c √(ρ t / D_e)
           = f_c Σ_e (A_e / 2) √(ρ t / D)_e

Against the reduction's count it is ×1.16 (squeak rig, 4.8 kHz: 25 vs 22), ×1.41 (door trim,
800 Hz: 298 vs 212), ×2.1 (instrument panel, 186 Hz: 54 vs 26) and ×0.43 (rattle rig, 400 Hz:
4 vs 10 — the steel strip's few low modes are below the asymptotic regime): a factor of ~2
either way. The clamped-edge term − Σ L_e k_e / 2π (the exact count of a plate with clamped
edges) was tried and does not help these models (the rattle rig's count goes below zero); the
leading term alone is exact to 3 % against a simply supported plate's spectrum once the edge
term of that boundary is taken off (tests/pipeline/checks/test_run_cost.py). A deck's shells
count with their own ρ t + NSM and √(D₁₁ D₂₂) (the rattle rig's deck gives its generator's
density); a matrices model states no mode count. The stated count follows the reduction's
rule (:func:`reduction_modes`): at least ``reduction.min_mode_count`` (10), so the rattle rig
says 10 (its run: 10), not Weyl's 4.

**Points.** A list of frequencies: its length. A sweep (arc-length continuation): between
:data:`SWEEP_POINTS_PER_BAND` / max_step (a smooth branch: the door trim, 105 at max_step 0.1,
204 at 0.05) and :data:`SWEEP_FOLD_FACTOR` × that (folds and contact switches: lumped rattle 234,
rattle rig 363, instrument panel sweep 400 at 0.1). ``resolution: auto``: H between :data:`AUTO_HARMONICS` (the shipped
searches chose 14 and 18; the search may go from 3 to 64) and N = max(64, 2^⌈log₂ 16 H⌉).

**Disk** (bytes, the files of ``output.files``): each file from its layout, with the compression
measured on the shipped cases (LZ4 of the VTU arrays ≈ :data:`VTU_RATIO`, gzip of response.h5's
contact time histories ≈ :data:`H5_GZIP_RATIO`); summary.json and table.txt by a per-point size
fitted on the shipped cases. A sweep with contacts may raise N up to
:func:`sarfe.hbm.continuation.most_samples` (N, contact rows) (64 N or more: N × rows ≤ 2^17);
the high end of N is the rule's N_hi ≤ that (Stiff contacts, below); response.h5 stores the
contact time histories at :func:`sarfe.results.record_grid.record_samples` (H, N, the case's N)
≤ max(the case's N, 64, 2^⌈log₂ 16 H⌉) samples (the decimated force, its per-bin peak and the
per-bin state), so its size is bounded by the case's N and H, not by the raised N.
Measured within ±30 % on the shipped cases (benchmarks/results/estimate.md).

**CPU** [s] (the process tree's user + system: a quiet 2-core machine's wall time is about this
over 1.5 with the point workers), stage by stage with constants measured on this machine
(benchmarks/results/point_cost.md, stages.md, large_panel.md, estimate.md):

    start + outputs      T_START + T_OUTPUT (FE: + the report's renders)
    mesh and assembly    c_a · n_dof
    Craig–Bampton        c_cb · n_dof · modes^0.71        (block Lanczos with shift-invert)
    H search (auto)      14 points at the low H (on the sweep's own linear stage)
    points               n_points · (c_0 + c_1 · (rows (2H+1))^0.55) · (2 for listed frequencies:
                         a cold start each) — Newton, error estimate, Hill stability, records
    mesh term            the linear stages of the two coarser meshes (√2 h, 2 h: ½ + ¼ of the
                         DOFs at the same modes, ¾ of the fine stage) and a point on each
                         (generated meshes; measured on door_trim_p1: 41.8 CPU s against the
                         fine linear stage's ≈ 51, benchmarks/results/door_trim.md)
    hard contacts        a sweep's raised N: + c_J E rows (2H+1) (N_hi − 16 N) a point, and the
                         points × max(1, ρ₁ / HARD_RATIO)^0.15; the impact check (below)

given as a range ×½ … ×2 around that (a sweep: ×1/√2 … ×√2 around its point range's ends):
an order of magnitude, never a promise (benchmarks/pipeline/bench_estimate.py compares it with
measured CPU s: benchmarks/results/estimate.md).

**Stiff contacts** (issue 30 item 4: at k_n ≥ 1e9 N/m the lumped and FE rattles took 2–3× the
old high end). How hard a contact is, is its own frequency against the excitation's:

    ω_c = max_c √(k_n,c / m_c),   ρ(k, f) = (ω_c / (2π k f))²   (ρ₁ = ρ(1, the band's lowest f))

the mass-line form of :mod:`sarfe.accuracy.contact_resolution`'s (6) (an impact lasts
τ_c = π / ω_c). m_c, the mass the normal row moves: a matrices model's 1 / (g M⁻¹ gᵀ) (exact;
lumped_rattle 0.143 kg: ρ₁ = 197 at its 1e6 N/m); an FE side moves :data:`PART_SHARE` = 33/140
of its part's mass (a cantilever tip's static shape), the two sides in series (rattle rig: strip
and plate 6.2 g, ρ₁ = 1.4e3; the shipped listed cases ρ₁ ≤ 3.2e3; a deck: unknown, not said).
Three terms grow with it, each measured (runs of this branch, nice 10, estimate.md):

- N. A sweep raises N at the turns of ω to 16 N (the shipped sweeps; c_0, c_1 were measured on
  them), a hard one (ρ₁ > HARD_RATIO) to 64 N at its stalled corners, and further where the
  aliasing check asks an impact for samples: N_hi = min(most_samples, max(16 N or 64 N,
  2^⌈log₂ 8 · 2√ρ₁⌉)) (T / τ_c = 2 √ρ₁ at the band's lowest f). Reached: lumped 4096 (k_n 1e6,
  1e7), 16384 (1e9), 32768 (1e10, 1e11; the rule 65536 there); rattle rig 4096 (2e5), 16384
  (1e7) — each the rule's N_hi but at 1e11.
  Each point's Newton Jacobians, aliasing checks and estimate re-solves (E =
  :data:`POINT_ITERATIONS`) cost c_J rows (2H+1) N each (c_J = :data:`AFT_S`: 9, 22, 61 ms an
  iteration at N = 2^10, 2^12, 2^14, 2 rows, H = 7). E = 14: the lumped rattle's points cost
  c_0 + c_1 (…)^0.55 + c_J E rows (2H+1) (N_hi − 16 N) with E = 14.8 at both 1e9 (344 CPU s,
  395 points — sweep 110 s, estimates and stability 185, impact check 44) and 1e10 (911 CPU s,
  555 points — 263, 596, 46); their points' mean N is 0.58 and 0.61 N_hi. The rattle rig 1e7's
  points are cheaper (E ≈ 3 on the same reading): its high end is ~8× its run.
- Points: × max(1, ρ₁ / :data:`HARD_RATIO`)^0.15 at both ends (measured: lumped 234 → 1280
  points over k_n 1e6 → 1e11, rattle rig 363 → 715 over 2e5 → 1e9; shipped sweeps: factor 1).
- The impact check (:mod:`sarfe.pipeline.solve.impact_check`: the loudest point integrated in
  time when ρ(H') > 4, H' = :func:`sarfe.accuracy.harmonic_truncation.extended_harmonics`):
  :data:`IMPACT_CHECK_S` (19 CPU s rattle rig 1e7, 57 lumped 1e10) in the high end when ρ(H') > 4
  at the band's lowest frequency, in the low end when also at its highest.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from sarfe.case.config import default_samples_per_period
from sarfe.accuracy.contact_resolution import RESOLUTION_LIMIT
from sarfe.accuracy.harmonic_truncation import extended_harmonics
from sarfe.hbm.continuation import MAX_SAMPLES_FACTOR, MAX_STALL_FACTOR, most_samples
from sarfe.mesh.geometry import triangle_areas
from sarfe.pipeline.model.cutoff import stage_cutoff_hz
from sarfe.pipeline.solve.case_accuracy import rule_cutoff_hz
from sarfe.pipeline.solve.mesh_error import coarse_sizes, mesh_error_reason
from sarfe.results.record_grid import COMPRESS_MIN_ENTRIES, record_samples

SWEEP_POINTS_PER_BAND = 10.0     # points × max_step of a smooth continuation (door trim)
SWEEP_FOLD_FACTOR = 4.0          # … × this with folds and contact switches (IP sweep: 400)
AUTO_HARMONICS = (8, 24)         # the H range the cost of resolution: auto is given for

# disk [bytes]
VTU_RATIO = 0.55                 # LZ4 of an ERP map's arrays (0.53–0.55 measured)
ANIMATION_RATIO = 0.6            # … of a deflection frame (0.59–0.63)
ANIMATION_FRAMES = 24
H5_GZIP_RATIO = 0.15             # gzip of response.h5's contact time histories (0.10–0.20)
H5_BASE = 40e3                   # response.h5's attributes, names, small datasets
PNG_BYTES = 300e3                # the plots (7 PNGs, 264–348 kB measured)
RENDER_BYTES = 300e3             # the report's surface renders (FE; 80–520 kB measured)
REPORT_BASE = 100e3              # report.html without its embedded files
SUMMARY_BASE = 15e3              # summary.json without the points
SUMMARY_POINT = (11.6e3, 2.3e3, 0.29e3)  # bytes per point: a + b · contacts + c · H (fitted
#                                         on the 6 shipped cases of estimate.md: 0.94–1.06)
TABLE_POINT = (120.0, 60.0)      # table.txt bytes per point: a + b · contacts
WAV_HEADER = 138                 # bytes of a sound.wav header; 16-bit mono samples follow
SAMPLE_RATE_HZ = 44100

# CPU [s]
T_START = 2.5                    # interpreter, imports, the case checks
T_OUTPUT = 3.5                   # summary, table, response.h5, plots, sound, report
T_OUTPUT_FE = 3.0                # … plus the report's renders and the VTU files
ASSEMBLY_S_PER_DOF = 5e-5        # mesh, checks, assembly (large_panel.md: ≈ 1e-4 at 1 M DOF)
CB_S = 6e-6                      # c_cb: Craig–Bampton s per DOF per (Weyl) mode^0.71
CB_MODE_EXPONENT = 0.71
POINT_S = (0.08, 0.01, 0.55)     # c_0, c_1, exponent of one point's cost
LISTED_POINT_FACTOR = 2.0        # listed frequencies start cold (no predictor)
SEARCH_POINTS = 14               # points of the H search: 8 screened, a ladder at the loudest
# stiff contacts (module docstring, "Stiff contacts")
HARD_RATIO = 5e3                 # ρ₁ = (ω_c / ω)² above which a sweep takes more points …
POINTS_EXPONENT = 0.15           # … ∝ (ρ₁ / HARD_RATIO)^this (lumped: 234 → 1280, k_n 1e6 → 1e11)
SAMPLES_PER_IMPACT = 8           # N ≥ this × T / τ_c at the band's lowest f (τ_c = π / ω_c)
AFT_S = 1.1e-7                   # c_J: s per sample × contact row × column (2H+1) of a Newton step
POINT_ITERATIONS = 14            # E: AFT Jacobians a reported point (sweep ≈ 5, estimates ≈ 9)
PART_SHARE = 33 / 140            # m_c of an FE side: this share of its part's mass (cantilever tip)
IMPACT_CHECK_S = (19.0, 57.0)    # the time-integration check of an unresolved impact (rattle rig
#                                  k_n = 1e7; lumped rattle 1e10), CPU s
RANGE = 2.0                      # the CPU range: central / RANGE … central × RANGE (a sweep:
#                                  √RANGE around its point range's ends)


@dataclass(frozen=True)
class ModelSize:
    """What a run's cost depends on, known before solving: ``dofs`` (free DOFs of the FE model,
    or the matrices' size), ``nodes``, ``triangles``, ``radiating_nodes`` (the ERP surface's
    nodes, or erp.dofs), ``contacts`` (count), ``contact_rows`` (rows of r = G u: 1 per rattle
    pair, 3 per FE squeak pair, the given DOFs of a matrices contact), ``friction_rows``,
    ``mode_density_per_hz`` (Weyl, None unknown), ``fe`` (a mesh model: VTU files),
    ``contact_mass_kg`` (per contact, in the case's order: the mass m_c its normal row moves,
    :func:`matrices_contact_mass` / :func:`fe_contact_mass`; nan without a normal row; ()
    unknown)."""

    dofs: int
    nodes: int = 0
    triangles: int = 0
    radiating_nodes: int = 0
    contacts: int = 0
    contact_rows: int = 0
    mode_density_per_hz: float | None = None
    fe: bool = False
    contact_mass_kg: tuple = ()


@dataclass(frozen=True)
class RunCost:
    """:func:`run_cost`'s answer. ``harmonics`` and ``samples`` (low, high) (equal unless
    ``resolution: auto``), ``cutoff_hz`` (None: a given mode count or no reduction), ``modes``
    (None: not estimated), ``points`` (low, high), ``cpu_s`` (low, high) [s], ``bytes``
    (low, high) written, ``files`` {file: (low, high) bytes}, ``auto`` (H chosen by the search)."""

    harmonics: tuple
    samples: tuple
    cutoff_hz: float | None
    modes: int | None
    points: tuple
    cpu_s: tuple
    bytes: tuple
    files: dict = field(default_factory=dict)
    auto: bool = False
    dofs: int = 0

    def as_dict(self) -> dict:
        """JSON-ready (summary.json ``cost_estimate``, validate --json)."""
        return {"harmonics": list(self.harmonics), "samples_per_period": list(self.samples),
                "cutoff_hz": self.cutoff_hz, "modes": self.modes, "points": list(self.points),
                "cpu_s": [round(v, 1) for v in self.cpu_s],
                "bytes": [int(v) for v in self.bytes], "resolution_auto": self.auto,
                "dofs": self.dofs,
                "files": {k: [int(a), int(b)] for k, (a, b) in self.files.items()}}


def weyl_mode_density(points, triangles, mass_per_area, bending) -> float:
    """Σ_e (A_e / 2) √(ρ t / D)_e [modes/Hz] (module docstring): points (n, 3) [m], triangles
    (n_e, 3), per triangle (scalars or (n_e,)) the mass per area ρ t [kg/m²] and the bending
    stiffness D [N·m] (an orthotropic section: √(D₁₁ D₂₂))."""
    area = triangle_areas(points, triangles)
    return float(np.sum(area / 2 * np.sqrt(np.asarray(mass_per_area, dtype=float)
                                           / np.asarray(bending, dtype=float))))


def plate_bending(thickness, young, poisson):
    """D = E t³ / (12 (1 − ν²)) [N·m] of an isotropic shell (arrays broadcast)."""
    t = np.asarray(thickness, dtype=float)
    return np.asarray(young, dtype=float) * t ** 3 / (12 * (1 - np.asarray(poisson) ** 2))


def contact_rows(config, pairs: dict | None) -> int:
    """Rows of r = G u of the case's contacts: per FE node pair 1 (rattle) or 3 (squeak: the
    normal and two tangents); a matrices contact its given normal_dof and tangential_dofs.
    ``pairs`` {contact name: node pairs} (FE) or None."""
    rows = 0
    for c in config.contacts:
        if pairs is not None:
            rows += int(pairs.get(c.name, 1)) * (3 if c.kind == "squeak" else 1)
        else:
            rows += (c.normal_dof is not None) + len(c.tangential_dofs or ())
    return rows


def matrices_contact_mass(mass, config) -> tuple:
    """m_c = 1 / (g M⁻¹ gᵀ) [kg] per contact of a matrices model: the mass its normal row
    r = g u moves (g: ±1 at ``normal_dof`` and −sign at ``relative_to``); nan without a normal
    row. ``mass`` (n, n) dense or sparse [kg]."""
    rows = [c.normal_dof for c in config.contacts]
    if not any(r is not None for r in rows):
        return tuple(math.nan for _ in rows)
    mass = mass.toarray() if hasattr(mass, "toarray") else np.asarray(mass, dtype=float)
    g = np.zeros((len(rows), mass.shape[0]))
    for i, ref in enumerate(rows):
        if ref is not None:
            g[i, ref.dof] = ref.sign
            if not isinstance(ref.relative_to, str):
                g[i, ref.relative_to] = -ref.sign
    try:
        flexibility = np.einsum("ij,ji->i", g, np.linalg.solve(mass, g.T))
    except np.linalg.LinAlgError:       # a singular M (massless DOFs): m_c not stated
        return tuple(math.nan for _ in rows)
    return tuple(float(1 / f) if r is not None and f > 0 else math.nan
                 for r, f in zip(rows, flexibility))


def fe_contact_mass(config, pairs: dict, triangles, part_of_triangle, triangle_mass) -> tuple:
    """m_c [kg] per FE contact: each side's node moves :data:`PART_SHARE` of the mass of its part
    (the part of a triangle holding it; a cantilever's tip: 33/140 of the strip, the static
    deflection's mass), the two sides in series (a ground side adds none); the lightest pair.
    ``pairs`` {name: (nodes_a, nodes_b)} (−1: ground), triangles (n_e, 3), part_of_triangle
    (n_e,) int, triangle_mass (n_e,) [kg]."""
    parts = np.bincount(part_of_triangle, weights=triangle_mass)
    node_part = np.full(int(np.max(triangles)) + 1, -1)
    for k in range(3):
        node_part[triangles[:, k]] = part_of_triangle
    out = []
    for c in config.contacts:
        a, b = (np.asarray(side, dtype=int) for side in pairs.get(c.name, ((), ())))
        if a.size == 0:
            out.append(math.nan)
            continue
        flexibility = np.zeros(a.size)
        for side in (a, b):
            known = (side >= 0) & (side < node_part.size)
            part = np.where(known, node_part[np.where(known, side, 0)], -1)
            mass = np.where(part >= 0, PART_SHARE * parts[np.maximum(part, 0)], np.inf)
            flexibility += 1 / np.where(mass > 0, mass, np.inf)     # ground, no part: none
        out.append(float(1 / np.max(flexibility)) if np.max(flexibility) > 0 else math.nan)
    return tuple(out)


def contact_frequency(config, size: ModelSize) -> float | None:
    """ω_c = max over contacts of √(k_n / m_c) [rad/s] (the contact's own frequency; an impact
    lasts τ_c = π / ω_c): None without a normal stiffness or a known m_c."""
    masses = size.contact_mass_kg
    if len(masses) != len(config.contacts):
        return None
    found = [math.sqrt(c.params["normal_stiffness_N_m"] / m)
             for c, m in zip(config.contacts, masses)
             if c.params.get("normal_stiffness_N_m") and math.isfinite(m) and m > 0]
    return max(found) if found else None


def stiffness_ratio(config, size: ModelSize, harmonic: int = 1, at: int = 0) -> float:
    """ρ(k) = (ω_c / (k ω))² at the band's lowest (``at`` 0) or highest (1) frequency (the mass-
    line form of :mod:`sarfe.accuracy.contact_resolution`'s (6)); 0 without ω_c."""
    omega_c = contact_frequency(config, size)
    if omega_c is None:
        return 0.0
    excitation = config.excitation
    f = excitation.max_frequency_hz if at else excitation.min_frequency_hz
    return (omega_c / (harmonic * 2 * math.pi * f)) ** 2


def sweep_points(config, size: ModelSize | None = None) -> tuple:
    """(low, high) reported points: a list's length, or a continuation's range, × the hard
    contacts' factor max(1, ρ₁ / HARD_RATIO)^POINTS_EXPONENT (docstring)."""
    excitation = config.excitation
    if excitation.sweep is None:
        n = len(excitation.frequency_hz)
        return n, n
    if not config.contacts:      # a linear sweep: evenly spaced points (initial_step apart)
        n = min(max(2, int(round(1.0 / config.solver.continuation.initial_step)) + 1), 101)
        return n, n
    hard = 1.0 if size is None else \
        max(1.0, stiffness_ratio(config, size) / HARD_RATIO) ** POINTS_EXPONENT
    low = SWEEP_POINTS_PER_BAND / config.solver.continuation.max_step * hard
    cap = config.solver.continuation.max_points
    return int(min(round(low), cap)), int(min(round(low * SWEEP_FOLD_FACTOR), cap))


def raised_samples(config, size: ModelSize, N: int) -> int:
    """The most AFT samples a sweep with contacts is taken to reach (docstring): 16 N (turns of
    ω, the shipped sweeps); 64 N (stalls at corners) with a hard contact (ρ₁ > HARD_RATIO); and
    at least :data:`SAMPLES_PER_IMPACT` × T / τ_c = 2 √ρ₁ (a power of 2: the aliasing check on
    an impact τ_c = π / ω_c); at most :func:`sarfe.hbm.continuation.most_samples`."""
    rho = stiffness_ratio(config, size)
    impact = SAMPLES_PER_IMPACT * 2 * math.sqrt(rho)
    need = 2 ** math.ceil(math.log2(impact)) if impact > 1 else 1
    turns = (MAX_STALL_FACTOR if rho > HARD_RATIO else MAX_SAMPLES_FACTOR) * N
    return int(min(most_samples(N, size.contact_rows), max(turns, need)))


def impact_check_seconds(config, size: ModelSize, H: int) -> tuple:
    """(low, high) CPU s of the time-integration check of the loudest point
    (:mod:`sarfe.pipeline.solve.impact_check`): run when its impact is not resolved by the
    estimate's H' (ρ(H') > RESOLUTION_LIMIT, (7)) — said in the high end when that holds at the
    band's lowest frequency, in the low end when it holds at its highest too; none without the
    error estimate."""
    if not config.solver.error_estimate or not config.contacts:
        return 0.0, 0.0
    extended = extended_harmonics(H)
    return tuple(IMPACT_CHECK_S[i] if stiffness_ratio(config, size, extended, at) >
                 RESOLUTION_LIMIT else 0.0 for i, at in ((0, 1), (1, 0)))


def _harmonics(config) -> tuple:
    solver = config.solver
    if solver.resolution == "auto" and config.contacts:
        return AUTO_HARMONICS
    return solver.harmonics, solver.harmonics


def _cutoff(case) -> float | None:
    config = case.config
    if not config.model.is_fe:
        return None
    if config.solver.resolution == "auto" and config.contacts:
        cutoff = rule_cutoff_hz(case)
        if cutoff is not None:
            return cutoff
    return stage_cutoff_hz(config)


def file_bytes(config, size: ModelSize, points: int, H: int, N: int, base_N: int | None = None
               ) -> dict:
    """{file: bytes} of ``output.files`` for ``points`` reported points at H, N (``base_N``:
    the case's N before a sweep raised it to N; docstring)."""
    files = set(config.output.files)
    out = {}
    n_c, rows = size.contacts, size.contact_rows
    if "summary" in files:
        a, b, c = SUMMARY_POINT
        out["summary.json"] = SUMMARY_BASE + (points + 1) * (a + b * n_c + c * H)
    if "table" in files:
        out["table.txt"] = 500 + points * (TABLE_POINT[0] + TABLE_POINT[1] * n_c)
    maps = map_count(config, points) if size.fe else 0
    if "response" in files:
        harmonic = 2 * (2 * H + 1) * rows * 8                    # displacement_m, force_N
        n = record_samples(H, N, base_N)                         # the stored time grid ≤ N
        history = 2 * n * rows * 8 + n * n_c                     # force_time_N, force_peak_N,
        #                                                          state (int8)
        ratio = H5_GZIP_RATIO if points * n * rows >= COMPRESS_MIN_ENTRIES else 1.0
        records = 8 * (5 * H + 4 * 14 + 2 * 28 + 40 + n_c * 30)  # erp, bands, audibility, …
        excitation = 0 if size.fe else 8 * (2 * H + 1) * size.dofs
        out["response.h5"] = (H5_BASE + points * (harmonic + records + excitation
                                                  + ratio * history)
                              + 8 * size.radiating_nodes * (1 + maps))
    cells = size.triangles * (3 * 8 + 8 + 1 + 4)      # connectivity, offsets, types, part_id
    if "erp_vtu" in files and size.fe:
        per_map = size.nodes * (8 * (H + 12) + 2 * 4 + 24) + cells
        out["ERP maps (VTU)"] = maps * (VTU_RATIO * per_map + 3e3)
    if "animation" in files and size.fe:
        frame = size.nodes * (4 + 24 + 8 + 24) + cells
        out["animation"] = ANIMATION_FRAMES * (ANIMATION_RATIO * frame + 1e3)
    wav = WAV_HEADER + 2 * SAMPLE_RATE_HZ * config.audibility.sound_duration_s
    if "sound" in files:
        out["sound.wav"] = 2 * wav                         # and sound_with_background.wav
    if "plots" in files:
        out["plots (PNG)"] = PNG_BYTES
    if "report" in files:
        out["report.html"] = REPORT_BASE + 4 / 3 * (PNG_BYTES + 2 * wav + (
            RENDER_BYTES if size.fe else 0.0))
    return out


def map_count(config, points: int) -> int:
    """ERP maps written (output.maps: :mod:`sarfe.pipeline.write.map_points`): the loudest, and
    every N-th point or the listed frequencies (at most ``points``)."""
    maps = config.output.maps
    if isinstance(maps, str):
        return min(1, points)
    if hasattr(maps, "keys"):
        return min(points, 1 + math.ceil(points / int(maps["every"])))
    return min(points, 1 + len(maps))


def point_seconds(rows: int, H: int, listed: bool, extra_samples: int = 0) -> float:
    """CPU s of one point (Newton, error estimate, Hill stability, records): c_0 + c_1 ·
    (rows (2H+1))^p, doubled for a listed frequency, + c_J E rows (2H+1) ΔN for ``extra_samples``
    ΔN AFT samples above the 16 N the shipped sweeps reach (a hard contact's raised N;
    docstring)."""
    c0, c1, p = POINT_S
    t = c0 + c1 * (max(rows, 1) * (2 * H + 1)) ** p
    aft = AFT_S * POINT_ITERATIONS * max(rows, 1) * (2 * H + 1) * max(extra_samples, 0)
    return t * (LISTED_POINT_FACTOR if listed else 1.0) + aft


def stage_seconds(dofs: int, modes) -> float:
    """CPU s of a linear stage: mesh, assembly and the Craig–Bampton modes (docstring)."""
    modes = 0 if modes is None else modes
    return ASSEMBLY_S_PER_DOF * dofs + CB_S * dofs * max(modes, 1) ** CB_MODE_EXPONENT


def reduction_modes(config, size: ModelSize, cutoff_hz) -> int | None:
    """The mode count the reduction keeps (sarfe.pipeline.model.fe_stage.reduce_model's rule):
    reduction.mode_count when given, else the Weyl count below the cutoff raised to
    reduction.min_mode_count (capped by the DOFs: the reduction's len(free) − len(boundary) − 1,
    here dofs − contact rows − 1). None without a Weyl density or a reduction."""
    reduction = config.reduction
    if size.mode_density_per_hz is None or reduction is None:
        return None
    if reduction.mode_count is not None:
        return int(reduction.mode_count)
    if cutoff_hz is None:
        return None
    weyl = int(round(size.mode_density_per_hz * cutoff_hz))
    floor = min(int(reduction.min_mode_count), max(size.dofs - size.contact_rows - 1, 0))
    return max(weyl, floor)


def run_cost(case, size: ModelSize) -> RunCost:
    """The cost of ``sarfe solve`` on ``case`` (a loaded Case) with ``size`` (docstring)."""
    config = case.config
    H = _harmonics(config)
    auto = config.solver.resolution == "auto" and bool(config.contacts)
    N = tuple(default_samples_per_period(h) for h in H) if auto \
        else (config.solver.samples_per_period,) * 2
    cutoff = _cutoff(case)
    modes = reduction_modes(config, size, cutoff)
    points = sweep_points(config, size)
    listed = config.excitation.sweep is None
    stage = stage_seconds(size.dofs, modes if modes is not None else 100) if size.fe else 0.0
    fixed = T_START + T_OUTPUT + (T_OUTPUT_FE if size.fe else 0.0) + stage
    if auto:
        fixed += SEARCH_POINTS * point_seconds(size.contact_rows, H[0], True)
    # the mesh term's coarser meshes (where it is due: mesh_error_reason's rule), their DOF
    # shares (h / h_c)² of a shell mesh; their stages keep the cutoff
    shares = [(config.model.fe.generator.mesh_size_m / h_c) ** 2 for h_c in coarse_sizes(case)] \
        if config.solver.error_estimate and mesh_error_reason(case) is None else []
    cpu, written, files = [], [], {}
    base = N
    if not listed and config.contacts:    # the N a sweep raises to (raised_samples)
        N = (N[0], raised_samples(config, size, N[1]))
    impact = impact_check_seconds(config, size, H[1])
    for i, (n, h, samples) in enumerate(((points[0], H[0], N[0]), (points[1], H[1], N[1]))):
        # c_0, c_1 were measured on sweeps that reach 16 N: the AFT term counts what is above
        t = fixed + n * point_seconds(size.contact_rows, h, listed,
                                      samples - MAX_SAMPLES_FACTOR * base[i]) \
            + sum(shares) * stage + len(shares) * point_seconds(size.contact_rows, h, True)
        spread = RANGE if listed else math.sqrt(RANGE)   # a sweep's points carry the rest
        cpu.append(t / spread + impact[0] if i == 0 else t * spread + impact[1])
        sizes = file_bytes(config, size, n, h, samples, base[i])
        written.append(sum(sizes.values()))
        for name, value in sizes.items():
            files.setdefault(name, []).append(value)
    return RunCost(harmonics=H, samples=N, cutoff_hz=cutoff, modes=modes, points=points,
                   cpu_s=tuple(cpu), bytes=tuple(written),
                   files={k: tuple(v) for k, v in files.items()}, auto=auto, dofs=size.dofs)


def _span(low, high, fmt) -> str:
    a, b = fmt(low), fmt(high)
    return a if a == b else f"{a}–{b}"


def _seconds(s) -> str:
    return f"{s:.2g}" if s < 100 else f"{s:.0f}"


def _megabytes(b) -> str:
    mb = b / 1e6
    return f"{mb:.2g}" if mb < 100 else f"{mb:.0f}"


def cost_lines(cost: RunCost, width: int = 80) -> list:
    """The validate/solve line, wrapped at ``width`` columns between its items (continuation
    lines indented by two), e.g.

        cost: H 10, N 64, cutoff 800 Hz, ≈ 298 modes, 31332 DOFs
          4 points, ≈ 14–54 s CPU, ≈ 14 MB written
    """
    H = _span(*cost.harmonics, str) + (" (auto)" if cost.auto else "")
    model = [f"H {H}", f"N {_span(*cost.samples, str)}"]
    if cost.cutoff_hz is not None:
        model.append(f"cutoff {cost.cutoff_hz:.0f} Hz")
    if cost.modes is not None:
        model.append(f"≈ {cost.modes} modes")
    if cost.dofs:
        model.append(f"{cost.dofs} DOFs")
    run = [f"{_span(*cost.points, str)} points", f"≈ {_span(*cost.cpu_s, _seconds)} s CPU",
           f"≈ {_span(*cost.bytes, _megabytes)} MB written"]
    one = "cost: " + ", ".join(model + run)
    if len(one) <= width:
        return [one]
    lines = ["cost: " + model[0]]
    for item in model[1:] + run:
        if item is run[0] or len(lines[-1]) + 2 + len(item) + 1 > width:   # + its comma
            lines[-1] += ","
            lines.append("  " + item)      # the run's items start a line of their own
        else:
            lines[-1] += ", " + item
    return lines


__all__ = ["ModelSize", "RunCost", "run_cost", "cost_lines", "weyl_mode_density", "plate_bending",
           "contact_rows", "sweep_points", "file_bytes", "map_count", "point_seconds",
           "stage_seconds", "reduction_modes", "matrices_contact_mass", "fe_contact_mass",
           "contact_frequency", "stiffness_ratio", "raised_samples",
           "impact_check_seconds"]
