"""Lazy package exports (PEP 562): a package names what it exports and where it lives, and the
module is imported on first use — so ``sarfe solve`` imports only what its case needs (matplotlib,
h5py, jinja2, pandas, dask … load when a figure, file or batch is made, not at start-up)."""
from __future__ import annotations

from importlib import import_module


def lazy_exports(package: str, exports: dict):
    """(``__getattr__``, ``__dir__``) for ``package``'s ``__init__``: ``exports`` maps an exported
    name to the module (absolute, or relative to ``package`` with a leading dot) that defines it;
    the first access imports that module and caches the name in the package."""
    namespace = import_module(package).__dict__

    def __getattr__(name):
        where = exports.get(name)
        if where is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(import_module(where, package), name)
        namespace[name] = value
        return value

    def __dir__():
        return sorted(set(namespace) | set(exports))

    return __getattr__, __dir__
