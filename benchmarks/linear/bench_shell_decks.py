"""Shell decks vs the commercial solver's stored modes, before/after issue 32, and shell
assembly time.

Decks: the public ones in ../shared/decks (plate_py.dat, mode_solid_shell_bar.bdf with their
stored frequencies in REFERENCE.json; plate.bdf's static displacements in
tests/fe/data/plate_op2_displacements.json) and, with ``--extra DIR``, three more decks of the
public pyNastran repository with the frequencies of their .op2 files (goland wing box, a bar +
plate deck, a real NX exhaust model whose geometry is read from its .op2). ``--fetch-extra
PYNASTRAN_GIT_DIR`` writes DIR from a pyNastran git checkout (needs pyNastran's OP2 reader).

"before" runs the same measurement on the sources of ``--before`` (git archive) (default: the commit
this work started from) in its own process; "after" runs this tree. Each deck's modes with
the deck's default element mass, and with the other mass. Timing: the 5 mm door trim's
``shell_matrices`` (generated meshes, best of 3 wall / CPU) and the exhaust deck's
``assemble_deck``.

Writes benchmarks/results/shell_decks.md and shell_decks.json.
Run: python benchmarks/bench_shell_decks.py [--extra DIR]
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import platform
import subprocess
import sys
import tempfile
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[1]
SHARED = next((p / "shared" / "decks" for p in ROOT.parents if (p / "shared" / "decks").is_dir()),
              ROOT.parent / "shared" / "decks")
BEFORE = "bf7347e"          # main at the start of issue 32's shell work
PYNASTRAN_COMMIT = "1d25a92442a76cd1b24bfd0bd4008644b79322b2"
_EXTRA = {  # name: (file in DIR, SPC set or None, rigid modes to skip, pyNastran op2 path)
    "goland": ("goland_final_test.bdf", 800, 0, "models/bugs/msc_dscmcol/goland_final_test"),
    "bar_plus_tri": ("random_test_bar_plus_tri.bdf", 1, 3,
                     "models/random/random_test_bar_plus_tri"),
    "exhaust": ("modal_example.bdf", 1, 0, "models/femap_exhaust/modal_example"),
}


def _decks(extra):
    reference = json.loads((SHARED / "REFERENCE.json").read_text())
    decks = {
        "plate_py": dict(path=str(SHARED / "plate_py.dat"), spc=None, skip=6,
                         reference=reference["plate_py.dat"]["frequencies_hz"][6:]),
        "mode_solid_shell_bar": dict(path=str(SHARED / "mode_solid_shell_bar.bdf"), spc=2, skip=0,
                                     reference=reference["mode_solid_shell_bar.bdf"]["frequencies_hz"]),
    }
    if extra:
        stored = json.loads((pathlib.Path(extra) / "reference.json").read_text())
        for name, (file, spc, skip, _) in _EXTRA.items():
            decks[name] = dict(path=str(pathlib.Path(extra) / file), spc=spc, skip=skip,
                               reference=stored[name][skip:skip + 10])
    return decks


# ---------------------------------------------------------------- worker (runs in either tree)
def _frequencies(system, fixed, count):
    import numpy as np
    import scipy.linalg as la
    import scipy.sparse.linalg as sla

    free = np.setdiff1d(np.arange(system.n_dofs), np.asarray(fixed, int))
    k, m = system.stiffness[free][:, free], system.mass[free][:, free]
    if k.shape[0] < 3000:   # M x = μ (K + s M) x tolerates a singular (lumped) M
        kd, md = k.toarray(), m.toarray()
        shift = 1e-3 * np.abs(np.diag(kd)).max() / np.abs(np.diag(md)).max()
        mu = np.sort(la.eigh(md, kd + shift * md, eigvals_only=True))[::-1][:count]
        return np.sqrt(np.abs(1.0 / mu - shift)) / (2 * np.pi)
    values = sla.eigsh(k.tocsc(), count, m.tocsc(), sigma=-1.0, which="LM",
                       v0=np.ones(k.shape[0]))[0]
    return np.sqrt(np.abs(np.sort(values))) / (2 * np.pi)


def _read(path):
    try:
        from sarfe.mesh.formats.nastran import read_nastran
    except ImportError:
        from sarfe.mesh.nastran import read_nastran
    return read_nastran(path)


def worker(spec):
    import numpy as np
    import scipy.sparse.linalg as sla

    from sarfe.fe.deck_assembly import assemble_deck, load_vector, support_dofs

    out = {"modes": {}, "timing": {}}
    if spec.get("timing_only"):
        return _timing(spec, out)
    for name, deck_spec in spec["decks"].items():
        deck = _read(deck_spec["path"])
        runs = {}
        for label, kwargs in (("default", {}), ("lumped", {"mass": "lumped"}),
                              ("consistent", {"mass": "consistent"})):
            start = time.perf_counter()
            system = assemble_deck(deck, **kwargs)
            seconds = time.perf_counter() - start
            fixed = (support_dofs(system, deck, deck_spec["spc"]) if deck_spec["spc"] is not None
                     else np.zeros(0, int))
            count = deck_spec["skip"] + len(deck_spec["reference"])
            hz = _frequencies(system, fixed, count)[deck_spec["skip"]:]
            runs[label] = dict(hz=hz.tolist(), assembly_s=seconds)
        out["modes"][name] = runs
    # plate.bdf: static in-plane displacements vs the stored ones
    deck = _read(str(SHARED / "plate.bdf"))
    table = np.array(json.loads((ROOT / "tests" / "fe" / "data" /
                                 "plate_op2_displacements.json").read_text())["displacements"])
    system = assemble_deck(deck)
    fixed = support_dofs(system, deck, 2)
    free = np.setdiff1d(np.arange(system.n_dofs), fixed)
    q = np.zeros(system.n_dofs)
    q[free] = sla.spsolve(system.stiffness[free][:, free].tocsc(),
                          load_vector(system, deck, 2)[free])
    u = system.displacement(q)[deck.node_index(table[:, 0].astype(int))]
    out["plate_static"] = dict(
        max_error=float(np.abs(u[:, :2] - table[:, 1:3]).max() / np.abs(table[:, 1:3]).max()),
        tip_ratio=float(u[table[:, 0] == 6, 0][0] / table[table[:, 0] == 6, 1][0]))
    return out


def _timing(spec, out):
    """Best-of-3 assembly times: the 5 mm door trim (generated mesh) and the exhaust deck."""
    import numpy as np

    from sarfe.fe.deck_assembly import assemble_deck
    from sarfe.fe.shell import shell_matrices
    from sarfe.mesh.generators import door_trim

    mesh = door_trim.generate(mesh_size=0.005)
    best, best_cpu = np.inf, np.inf
    for _ in range(3):
        start, start_cpu = time.perf_counter(), time.process_time()
        shell_matrices(mesh.points, mesh.triangles, 2.5e-3, 2.2e9, 0.35, 1050.0)
        best = min(best, time.perf_counter() - start)
        best_cpu = min(best_cpu, time.process_time() - start_cpu)
    out["timing"]["door_trim_5mm"] = dict(triangles=len(mesh.triangles), wall_s=best,
                                          cpu_s=best_cpu)
    for variant in spec.get("door_variants", []):
        best = np.inf
        for _ in range(3):
            start = time.perf_counter()
            shell_matrices(mesh.points, mesh.triangles, 2.5e-3, 2.2e9, 0.35, 1050.0, **variant)
            best = min(best, time.perf_counter() - start)
        out["timing"]["door_trim_5mm " + ",".join(f"{k}={v}" for k, v in variant.items())] = dict(
            triangles=len(mesh.triangles), wall_s=best)
    if "exhaust" in spec["decks"]:
        deck = _read(spec["decks"]["exhaust"]["path"])
        best = np.inf
        for _ in range(3):
            start = time.perf_counter()
            assemble_deck(deck)
            best = min(best, time.perf_counter() - start)
        out["timing"]["exhaust_deck"] = dict(triangles=int(deck.shells.n_triangles), wall_s=best)
    return out


# ---------------------------------------------------------------- driver
def _run(tree, spec):
    env = dict(os.environ, PYTHONPATH=str(tree), OPENBLAS_NUM_THREADS="1")
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as handle:
        json.dump(spec, handle)
    try:
        result = subprocess.run([sys.executable, str(HERE / "bench_shell_decks.py"), "--worker",
                                 handle.name], capture_output=True, text=True, env=env,
                                cwd=str(tree), check=True)
    finally:
        os.unlink(handle.name)
    return json.loads(result.stdout.strip().splitlines()[-1])


def fetch_extra(pynastran_git, target):
    """Decks and stored frequencies of _EXTRA from a pyNastran git checkout (at the pinned
    commit); the exhaust's bulk data is written from its .op2 geometry tables."""
    import numpy as np

    if not hasattr(np, "in1d"):
        np.in1d = np.isin
    from pyNastran.op2.op2 import read_op2
    from pyNastran.op2.op2_geom import read_op2_geom

    target = pathlib.Path(target)
    target.mkdir(parents=True, exist_ok=True)
    reference = {"source": f"pyNastran {PYNASTRAN_COMMIT}: eigenvalues of the .op2 files"}
    for name, (file, _, _, stem) in _EXTRA.items():
        op2_path = target / (pathlib.Path(stem).name + ".op2")
        op2_path.write_bytes(subprocess.run(
            ["git", "--git-dir", str(pynastran_git), "show", f"{PYNASTRAN_COMMIT}:{stem}.op2"],
            capture_output=True, check=True).stdout)
        if name == "exhaust":
            model = read_op2_geom(str(op2_path), debug=None, build_dataframe=False)
            model.write_bdf(str(target / file), size=16)
        else:
            (target / file).write_bytes(subprocess.run(
                ["git", "--git-dir", str(pynastran_git), "show", f"{PYNASTRAN_COMMIT}:{stem}.bdf"],
                capture_output=True, check=True).stdout)
            model = read_op2(str(op2_path), debug=None, build_dataframe=False)
        eigen = next(iter(model.eigenvalues.values()))
        reference[name] = [float(f) for f in eigen.cycles]
    (target / "reference.json").write_text(json.dumps(reference, indent=1))


def _best(runs):
    """Per timing row, the run with the smallest wall time."""
    return {key: min((run[key] for run in runs), key=lambda row: row["wall_s"])
            for key in runs[0]}


def _table(decks, before, after):
    lines = ["| deck | mode | reference [Hz] | before, consistent (old default) | before, lumped | "
             "after, default | after, other mass |", "|---|---|---|---|---|---|---|"]
    for name, spec in decks.items():
        b, a = before["modes"][name], after["modes"][name]
        other = "consistent" if a["default"]["hz"] == a["lumped"]["hz"] else "lumped"
        for i, ref in enumerate(spec["reference"]):
            def pct(run):
                return f"{100 * (run['hz'][i] / ref - 1):+.2f} %"
            lines.append(f"| {name} | {spec['skip'] + i + 1} | {ref:.4g} | {pct(b['consistent'])} | "
                         f"{pct(b['lumped'])} | **{pct(a['default'])}** | {pct(a[other])} |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--worker")
    parser.add_argument("--before", default=BEFORE)
    parser.add_argument("--extra", help="folder written by --fetch-extra")
    parser.add_argument("--fetch-extra", nargs=2, metavar=("PYNASTRAN_GIT_DIR", "TARGET"))
    args = parser.parse_args()
    if args.worker:
        print(json.dumps(worker(json.loads(pathlib.Path(args.worker).read_text()))))
        return
    if args.fetch_extra:
        fetch_extra(*args.fetch_extra)
        return
    decks = _decks(args.extra)
    spec = {"decks": decks}
    with tempfile.TemporaryDirectory() as folder:   # the "before" sources, git archive'd
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.before, "sarfe"],
                                 capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", folder], input=archive, check=True)
        before = _run(pathlib.Path(folder), spec)
        after = _run(ROOT, spec)
        # timing: before and after in turn, twice (A B A B), best of all
        variants = [{"membrane": "andes"}, {"mass": "lumped"}]
        timing_b, timing_a = [], []
        for _ in range(2):
            timing_b.append(_run(pathlib.Path(folder), dict(spec, timing_only=True))["timing"])
            timing_a.append(_run(ROOT, dict(spec, timing_only=True,
                                            door_variants=variants))["timing"])
    before["timing"], after["timing"] = _best(timing_b), _best(timing_a)
    results = dict(before_ref=args.before, decks=decks, before=before, after=after,
                   machine=platform.machine(), load=os.getloadavg()[0])
    (ROOT / "benchmarks" / "results").mkdir(exist_ok=True)
    (ROOT / "benchmarks" / "results" / "shell_decks.json").write_text(json.dumps(results, indent=1))
    bt, at = before["timing"], after["timing"]
    lines = [
        "# Shell decks vs the commercial solver's stored modes (issue 32)", "",
        f"Before = `{args.before}` (Allman membrane + drilling penalty 1e-2, DKT without transverse "
        "shear, CQUAD4 split in two triangles; `sarfe solve` used the consistent mass). After = this "
        "tree's deck defaults: lumped mass unless PARAM,COUPMASS > 0; CQUAD4 membrane = incompatible-"
        "mode quad (QM6), CTRIA3 = constant-strain triangle, both with the drilling penalty "
        "1e-6·K6ROT; DKMT bending where the section gives transverse shear (MID3), DKT otherwise. "
        "Per mode: (sarfe / reference − 1). Target: 1 %.", "",
        *_table(decks, before, after), "",
        f"plate.bdf (static, 5 × 5 CQUAD4 in tension): largest in-plane displacement error vs the "
        f"stored result {100 * before['plate_static']['max_error']:.2f} % before, "
        f"{100 * after['plate_static']['max_error']:.4f} % after.", "",
        "## Assembly time", "",
        "| what | before [s] | after [s] |", "|---|---|---|",
        f"| door trim 5 mm, `shell_matrices` ({at['door_trim_5mm']['triangles']} triangles), wall | "
        f"{bt['door_trim_5mm']['wall_s']:.2f} | {at['door_trim_5mm']['wall_s']:.2f} |",
        f"| same, CPU | {bt['door_trim_5mm']['cpu_s']:.2f} | {at['door_trim_5mm']['cpu_s']:.2f} |",
    ]
    for key, row in at.items():
        if key.startswith("door_trim_5mm "):
            lines.append(f"| {key.replace('door_trim_5mm ', 'door trim 5 mm, ')}, wall | – | "
                         f"{row['wall_s']:.2f} |")
    if "exhaust_deck" in at:
        lines.append(f"| exhaust deck `assemble_deck` ({at['exhaust_deck']['triangles']} facets), "
                     f"wall | {bt['exhaust_deck']['wall_s']:.2f} | {at['exhaust_deck']['wall_s']:.2f} |")
    lines += ["", f"Best of 3 × 2 (before and after in turn, A B A B), one BLAS thread, {platform.machine()}, load average "
              f"{results['load']:.1f} at the end (shared machine: times are upper bounds)."]
    (ROOT / "benchmarks" / "results" / "shell_decks.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
