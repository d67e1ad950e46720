"""Moved to :mod:`sarfe.accuracy.estimates` (the estimators live below the pipeline, issue 12);
this alias keeps ``sarfe.study.accuracy`` imports working."""
from sarfe.accuracy.estimates import *  # noqa: F401,F403
from sarfe.accuracy.estimates import __all__  # noqa: F401
