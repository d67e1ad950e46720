"""sarfe.tradeoff — the speed/accuracy trade of a case (``sarfe study``).

Modules: study (one knob at a time around a case's settings → table, CSV, JSON, Pareto PNG),
lumped (small stand-in problems), cli (``register(subparsers)``). The error estimates and the
accuracy resolution it measures live in :mod:`sarfe.accuracy` and
:mod:`sarfe.pipeline.solve.case_accuracy`; contact screening in :mod:`sarfe.hbm.pruning`.
"""
