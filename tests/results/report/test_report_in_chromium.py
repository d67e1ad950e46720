"""The report rendered in headless Chromium (issue 31): the DOM the browser builds holds the
verdict, the ranking and two playable audio controls (the predicted sound and it mixed with the
cabin background), and the page renders to a screenshot. Skipped where no Chromium is installed."""
import re
import shutil
import subprocess

import pytest

from sarfe.cli import main
from tests.small_cases import TINY

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")


@pytest.mark.skipif(CHROMIUM is None, reason="no Chromium on this machine")
def test_report_shows_verdict_ranking_and_audio_in_chromium(tmp_path):
    case = tmp_path / "case.yaml"      # 60 N: the stop closes (a rattle), audible over the cabin
    case.write_text(TINY.replace("force_N: 1.0", "force_N: 60.0").replace(
        "output: {files: [summary, table]}", "output: {files: [summary, report, sound, plots]}"))
    out = tmp_path / "out"
    assert main(["solve", str(case), "--output", str(out), "--quiet"]) == 0
    page = (out / "report.html").as_uri()
    flags = ["--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars"]
    dom = subprocess.run([CHROMIUM, *flags, "--dump-dom", page], capture_output=True, text=True,
                         timeout=120).stdout
    assert re.search(r'id="verdict"[^>]*class="verdict (audible|inaudible)"|'
                     r'class="verdict (audible|inaudible)"[^>]*id="verdict"', dom)
    assert 'id="verdict-answer"' in dom and 'id="verdict-top"' in dom and 'id="verdict-fix"' in dom
    assert 'id="ranking-table"' in dom and ">stop<" in dom
    audio = re.findall(r'<audio[^>]*\bcontrols\b[^>]*src="data:audio/wav;base64,', dom)
    assert len(audio) == 2
    shot = tmp_path / "report.png"
    subprocess.run([CHROMIUM, *flags, f"--screenshot={shot}", "--window-size=1280,2000", page],
                   capture_output=True, timeout=120)
    assert shot.is_file() and shot.stat().st_size > 20_000
