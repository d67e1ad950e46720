"""The lock file (constraints.txt) pins every dependency of pyproject.toml to one exact version,
and `make setup` installs it as it is, so a fresh machine gets what the tests passed with."""
import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def normalized(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def locked_versions() -> dict:
    pins = {}
    for line in (ROOT / "constraints.txt").read_text().splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            name, _, version = line.partition("==")
            assert version, f"constraints.txt: '{line}' is not an exact pin (name==version)"
            pins[normalized(name)] = version
    return pins


def test_every_dependency_is_locked_exactly():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    wanted = project["dependencies"] + [d for extra in project["optional-dependencies"].values()
                                        for d in extra]
    pins = locked_versions()
    missing = [d for d in wanted
               if normalized(re.match(r"[A-Za-z0-9_.-]+", d).group()) not in pins]
    assert not missing, f"not in constraints.txt (run 'make lock'): {missing}"
    assert "sarfe" not in pins


def test_setup_installs_from_the_lock_file():
    makefile = (ROOT / "Makefile").read_text()
    assert "pip install -q --no-deps -r $(LOCK)" in makefile
    assert "LOCK   := constraints.txt" in makefile
    assert "make test" in (ROOT / ".ci" / "run").read_text()
    # `make test` / `make demo` install sarfe with every extra (the batch tests need `batch`)
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    installed = re.search(r"pip install -q --no-deps -e '\.\[([a-z,]+)\]'", makefile)
    assert installed and set(installed.group(1).split(",")) == set(extras)
