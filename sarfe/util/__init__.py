"""Utilities below every layer: lazy (lazy package exports, PEP 562), workers (an ordered map on
forked worker processes), parent_watch (child processes that die with their parent, SIGKILL
included), progress (tqdm bars or one line per stage)."""
