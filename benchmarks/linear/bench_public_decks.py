"""Public decks read as they are, against the stored results of the solver that ran them (issue 32).

Decks: tests/data/decks (pyNastran's models/ and two CalculiX tests, SOURCE.md and REFERENCE.json:
support set, the cards a case would ignore, stored frequencies) and the shared decks of
../shared/decks that carry frequencies (plate_py free-free, mode_solid_shell_bar). Per deck:
whether it reads (or the one line it is refused with), its first ≤ 6 elastic modes with the deck's
default mass (CalculiX decks: the consistent mass CalculiX uses) against the stored ones, its mass against pyNastran's mass properties (an independent
implementation), and the read + assembly + eigen time. "before" runs the same worker on the
sources of ``--before`` (default: main where this work started) in its own process.

Writes benchmarks/results/public_decks.md and public_decks.json.
Run: python benchmarks/linear/bench_public_decks.py [--before REF]
"""
from __future__ import annotations

import argparse
import json
import pathlib
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
import benchlib  # noqa: E402

HERE = pathlib.Path(__file__).resolve()
DECKS = benchlib.ROOT / "tests" / "data" / "decks"
SHARED = next((p / "shared" / "decks" for p in benchlib.ROOT.parents
               if (p / "shared" / "decks").is_dir()), benchlib.ROOT.parent / "shared" / "decks")
BEFORE = "8eb48b7"        # main when issue 32 items 1, 3, 7 started


def _decks() -> dict:
    """{name: dict(path, support_set, rigid_modes, reference)} of every deck with frequencies."""
    decks = {}
    stored = json.loads((DECKS / "REFERENCE.json").read_text())
    for name, spec in stored.items():
        if isinstance(spec, dict) and ("frequencies_hz" in spec or "refused" in spec):
            decks[name] = dict(path=str(DECKS / name), support_set=spec.get("support_set"),
                               rigid_modes=spec.get("rigid_modes", 0),
                               reference=spec.get("frequencies_hz", [])[:6],
                               mass=spec.get("mass"),     # the solver's, if not the deck default
                               note=spec.get("note") if "refused_cards" not in spec else None)
    if (SHARED / "REFERENCE.json").is_file():
        shared = json.loads((SHARED / "REFERENCE.json").read_text())
        decks["plate_py.dat"] = dict(path=str(SHARED / "plate_py.dat"), support_set=None,
                                     rigid_modes=6,
                                     reference=shared["plate_py.dat"]["frequencies_hz"][6:12])
        decks["mode_solid_shell_bar.bdf"] = dict(
            path=str(SHARED / "mode_solid_shell_bar.bdf"), support_set=2, rigid_modes=0,
            reference=shared["mode_solid_shell_bar.bdf"]["frequencies_hz"][:6])
    return decks


# ---------------------------------------------------------------- worker (runs in either tree)
def worker(decks: dict) -> dict:
    import numpy as np
    import scipy.linalg as la

    if not hasattr(np, "in1d"):
        np.in1d = np.isin
    from sarfe.fe.deck_assembly import assemble_deck, mass_properties, support_dofs
    from sarfe.mesh.formats.deck import DeckError

    out = {}
    for name, spec in decks.items():
        start = time.perf_counter()
        try:
            if spec["path"].endswith(".inp"):
                from sarfe.mesh.formats.abaqus import read_abaqus
                deck = read_abaqus(spec["path"])
            else:
                from sarfe.mesh.formats.nastran import nastran_deck
                deck = nastran_deck(spec["path"])
            if spec["path"].endswith(".inp") and deck.unsupported:   # what a case is refused with
                raise DeckError("unsupported: " + ", ".join(
                    f"{k} ({v})" for k, v in sorted(deck.unsupported.items())))
            if not spec["reference"]:
                out[name] = dict(read=True, unsupported=dict(deck.unsupported))
                continue
            system = assemble_deck(deck, **({"mass": spec["mass"]} if spec.get("mass") else {}))
        except Exception as error:    # noqa: BLE001 — the one line a deck is refused with
            out[name] = dict(read=False, error=" ".join(str(error).split())[:300])
            continue
        fixed = (support_dofs(system, deck, spec["support_set"])
                 if spec["support_set"] is not None else np.zeros(0, int))
        free = np.setdiff1d(np.arange(system.n_dofs), fixed)
        k = system.stiffness[free][:, free].toarray()
        m = system.mass[free][:, free].toarray()
        shift = 1e-3 * np.abs(np.diag(k)).max() / np.abs(np.diag(m)).max()
        count = spec["rigid_modes"] + len(spec["reference"])
        mu = np.sort(la.eigh(m, k + shift * m, eigvals_only=True))[::-1][:count]
        hz = np.sqrt(np.abs(1.0 / mu - shift)) / (2 * np.pi)
        out[name] = dict(read=True, hz=hz[spec["rigid_modes"]:].tolist(),
                         mass=float(mass_properties(deck)[0]), seconds=time.perf_counter() - start,
                         unsupported=dict(deck.unsupported), dofs=int(system.n_dofs))
    return out


def _pynastran_mass(path: str) -> float | None:
    import numpy as np

    if not hasattr(np, "in1d"):
        np.in1d = np.isin
    from pyNastran.bdf.bdf import read_bdf
    from pyNastran.bdf.mesh_utils.mass_properties import mass_properties

    if path.endswith(".inp"):
        return None
    model = read_bdf(path, debug=None, xref=True)
    wtmass = model.params["WTMASS"].values[0] if "WTMASS" in model.params else 1.0
    return float(mass_properties(model)[0] * wtmass)


def _run(tree: pathlib.Path, decks: dict) -> dict:
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as handle:
        json.dump(decks, handle)
    try:
        result = subprocess.run([sys.executable, str(HERE), "--worker", handle.name],
                                capture_output=True, text=True, env=benchlib.child_env(tree),
                                cwd=str(tree), check=True)
    finally:
        pathlib.Path(handle.name).unlink()
    return json.loads(result.stdout.strip().splitlines()[-1])


def _cell(run, reference):
    if not run.get("read"):
        return f"refused: {run.get('error', '')[:200]}"
    if "hz" not in run:
        return "read"
    errors = [h / r - 1 for h, r in zip(run["hz"], reference)]
    return f"{100 * max(errors, key=abs):+.3f} %"


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--worker")
    parser.add_argument("--before", default=BEFORE)
    args = parser.parse_args()
    if args.worker:
        print(json.dumps(worker(json.loads(pathlib.Path(args.worker).read_text()))))
        return
    decks = _decks()
    with tempfile.TemporaryDirectory() as folder:
        archive = subprocess.run(["git", "-C", str(benchlib.ROOT), "archive", args.before, "sarfe"],
                                 capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", folder], input=archive, check=True)
        before = _run(pathlib.Path(folder), decks)
    after = _run(benchlib.ROOT, decks)
    lines = ["# Public decks vs their stored frequencies (issue 32)", "",
             f"Before = `{args.before}`, after = this tree; deck defaults (lumped mass unless "
             "PARAM,COUPMASS > 0; CalculiX decks consistent, as CalculiX). Max mode error = the largest |sarfe / stored − 1| of the first ≤ 6 "
             "elastic modes (signed); mass error = sarfe / pyNastran's mass properties − 1. Target: "
             "1 % and 1e-6.", "",
             "| deck | modes | before: max mode error | after: max mode error | after: per mode [%] "
             "| mass error | DOFs | read + assemble + eigen [s] |",
             "|---|---|---|---|---|---|---|---|"]
    for name, spec in decks.items():
        a, b = after[name], before[name]
        mass_error = "–"
        if a.get("read") and "mass" in a:
            expected = _pynastran_mass(spec["path"])
            if expected:
                mass_error = f"{a['mass'] / expected - 1:.1e}"
        per_mode = (" ".join(f"{100 * (h / r - 1):+.3f}" for h, r in zip(a["hz"], spec["reference"]))
                    if "hz" in a else "–")
        lines.append(f"| {name} | {len(spec['reference'])} | {_cell(b, spec['reference'])} | "
                     f"**{_cell(a, spec['reference'])}** | {per_mode} | {mass_error} | "
                     f"{a.get('dofs', '–')} | {a.get('seconds', 0):.2f} |")
    lines += [""] + [f"- {name}: {spec['note']}" for name, spec in decks.items() if spec.get("note")]
    lines += ["", benchlib.machine_line()]
    benchlib.write_results("public_decks", dict(before_ref=args.before, decks=decks, before=before,
                                                after=after, machine=benchlib.machine()), lines)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
