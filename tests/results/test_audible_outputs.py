"""Issue 31 wiring at pipeline level (slow: one full solve of the shipped lumped rattle):
audibility in summary.json, --quiet output, 80-column console, report with verdict, ranking,
audio controls and the case file path."""
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.slow
def test_lumped_rattle_audibility_outputs(tmp_path):
    out = tmp_path / "lr"
    case = ROOT / "cases" / "lumped_rattle.yaml"
    run = subprocess.run([sys.executable, "-m", "sarfe", "solve", str(case), "--output", str(out),
                          "--force", "--quiet"], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode in (0, 3), run.stderr
    lines = run.stdout.strip().splitlines()
    assert len(lines) == 2 and lines[1].startswith("results:")      # one result line + the path
    summary = json.loads((out / "summary.json").read_text())
    audibility = summary["worst"]["audibility"]
    for key in ("spl_dba", "loudness_sone", "audible", "margin_db"):
        assert key in audibility
    assert isinstance(audibility["audible"], bool)
    assert set(audibility["contacts"]) == {c["name"] for c in summary["contacts"]}
    assert "sensitivities" in summary["worst"] and "onset" in summary["worst"]
    html = (out / "report.html").read_text()
    assert "<audio" in html and " controls" in html
    assert "AUDIBLE" in html.upper() and "ranking" in html.lower()
    assert "lumped_rattle.yaml" in html and "case file None" not in html
    assert (out / "sound.wav").exists() and (out / "sound_with_background.wav").exists()
    full = subprocess.run([sys.executable, "-m", "sarfe", "solve", str(case), "--output",
                           str(tmp_path / "lr2"), "--force"], capture_output=True, text=True,
                          cwd=ROOT)
    wide = [line for line in full.stdout.splitlines()                # the path line holds a path
            if len(line) > 80 and not line.startswith("results:")]
    assert wide == []
