"""Stability verdicts and both contact-row counts (at H and at the check H' = ⌊3H/4⌋) per point
of a sweep, for comparing two sarfe trees on the same orbits (issue 15, session hillshare).

    python benchmarks/tools/stability_counts.py capture CASE.yaml POINTS.pkl   # solve, keep the orbits
    python benchmarks/tools/stability_counts.py evaluate POINTS.pkl OUT.json    # with this tree (or
                                                                          # $PYTHONPATH's sarfe)
    python benchmarks/tools/stability_counts.py compare BEFORE.json AFTER.json

``capture`` runs the case (set ``solver: {workers: 1}``) and pickles the inputs of every
:func:`sarfe.hbm.solve.stability` call (problem, ω, U, AFT forces, options). ``evaluate`` computes
per point the verdict (``stability``, as the solver does), the count at H and the count at H'
(with a tree before the shared contour: ``contact_row_count`` and ``stability_trust.count_at``,
each on its own contour), the det F evaluations of the count's contour (``evaluations``, None
where no contour was sampled) and the CPU seconds of ``stability``. ``compare`` lists the points
where verdict, either count or the leading exponent (relative 10⁻⁶) differ, the total CPU and the
mean evaluations.
"""
import json
import pathlib
import pickle
import sys
import time
import types

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
import benchlib  # noqa: E402,F401  (one BLAS thread; PYTHONPATH's sarfe, else this tree's)


def capture(case_path, out):
    import sarfe.hbm.solve as solve_module
    from sarfe.pipeline import load_case
    from sarfe.pipeline.run import solve_case

    records, original = [], solve_module.stability

    def kept(problem, omega, U, ev, options):
        records.append((problem, omega, U, ev.forces, options))
        return original(problem, omega, U, ev, options)

    solve_module.stability = kept
    solve_case(load_case(case_path), write=False)
    with open(out, "wb") as f:
        pickle.dump(records, f)
    print(len(records), "points")


def evaluate(points_path, out):
    import numpy as np
    import sarfe.hbm.solve as solve_module
    import sarfe.hbm.stability.rows as rows
    import sarfe.hbm.stability.trust as trust
    from sarfe.hbm.stability.contact_terms import ContactOperator

    with open(points_path, "rb") as f:
        records = pickle.load(f)
    sampled = {}
    winding_counts = rows.winding_counts

    def counted(*args, **kwargs):          # the count's contour: keep its evaluations
        counts, evaluations = winding_counts(*args, **kwargs)
        sampled.setdefault("evaluations", evaluations)
        return counts, evaluations

    points = []
    for problem, omega, U, forces, options in records:
        t = time.process_time()
        r = solve_module.stability(problem, omega, U, types.SimpleNamespace(
            forces=forces, jacobian=None), options)
        cpu = time.process_time() - t
        check = trust.check_harmonics(problem.harmonics)
        op = ContactOperator(problem, U, omega, forces)
        args = (problem.model, problem.contacts, omega, problem.harmonics, forces, op)
        sampled.clear()
        rows.winding_counts = counted
        if hasattr(rows, "contact_row_counts"):
            _, zeros, coarse = rows.contact_row_counts(*args, tolerance=options.stability_tolerance,
                                                       check_harmonics=check)
        else:
            zeros = rows.contact_row_count(*args, tolerance=options.stability_tolerance)[1]
            coarse = trust.count_at(problem, omega, U, forces, check,
                                    options.stability_tolerance)[1]
        rows.winding_counts = winding_counts
        points.append(dict(frequency_hz=float(omega / (2 * np.pi)), stable=r.stable,
                           leading=float(r.leading), note=r.note, zeros=zeros, coarse=coarse,
                           evaluations=sampled.get("evaluations"), cpu_s=cpu))
    with open(out, "w") as f:
        json.dump(points, f, indent=1)
    print(len(points), "points, stability CPU", round(sum(p["cpu_s"] for p in points), 1), "s")


def compare(before_path, after_path):
    with open(before_path) as f:
        before = json.load(f)
    with open(after_path) as f:
        after = json.load(f)
    assert len(before) == len(after), (len(before), len(after))
    differ = 0
    for p, q in zip(before, after):
        lead = p["leading"] != p["leading"] or abs(p["leading"] - q["leading"]) <= 1e-6 * max(
            1.0, abs(p["leading"]))
        if not lead or any(p[k] != q[k] for k in ("stable", "zeros", "coarse")):
            differ += 1
            print("differs", p["frequency_hz"], {k: (p[k], q[k]) for k in
                                                 ("stable", "zeros", "coarse", "leading")})
    print(f"{len(before)} points, {differ} differ; stability CPU "
          f"{sum(p['cpu_s'] for p in before):.1f} -> {sum(p['cpu_s'] for p in after):.1f} s")
    counted = [(p.get("evaluations"), q.get("evaluations")) for p, q in zip(before, after)]
    counted = [(a, b) for a, b in counted if a is not None and b is not None]
    if counted:
        print(f"det F evaluations per counted point ({len(counted)}): "
              f"{sum(a for a, _ in counted) / len(counted):.1f} -> "
              f"{sum(b for _, b in counted) / len(counted):.1f}")
    return differ


if __name__ == "__main__":
    command, a, b = sys.argv[1:4]
    {"capture": capture, "evaluate": evaluate, "compare": compare}[command](a, b)
