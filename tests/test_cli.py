"""The ``sarfe`` command: version, help, subcommands, validate."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import sarfe
from sarfe import cli

CASES = Path(__file__).resolve().parents[1] / "cases"


def test_version(capsys):
    with pytest.raises(SystemExit) as info:
        cli.main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"sarfe {sarfe.__version__}"


def test_no_command_prints_help_exit_2(capsys):
    assert cli.main([]) == 2
    assert "solve" in capsys.readouterr().out


def test_console_script_and_module_entry_point():
    script = Path(sys.executable).with_name("sarfe")
    command = [str(script)] if script.exists() else [sys.executable, "-m", "sarfe"]
    proc = subprocess.run(command + ["validate", str(CASES / "lumped_rattle.yaml")],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines()[0].strip().endswith("valid")
    assert proc.stdout.splitlines()[1].startswith("cost: H 7, N 256")


def test_study_and_batch_subcommands_are_registered(capsys):
    """``sarfe study`` (sarfe.tradeoff.cli) and ``sarfe batch`` (sarfe.batch.cli) are subcommands."""
    parser = cli.build_parser()
    for command in ("solve", "verify", "validate", "study", "batch"):
        with pytest.raises(SystemExit) as info:
            parser.parse_args([command, "--help"])
        assert info.value.code == 0
        assert f"usage: sarfe {command}" in capsys.readouterr().out


def test_validate_reports_pairs(capsys):
    assert cli.main(["validate", str(CASES / "rattle_rig.yaml")]) == 0
    assert "tip (1 pairs)" in capsys.readouterr().out
