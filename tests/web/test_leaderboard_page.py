"""A competition run end to end (``usarsim compete``, on local Ray): two of the shipped brains
as teams over two hidden variants of the yellow arena, the leaderboard's CSV and Parquet, and its
HTML page in a real headless browser (Chromium through Playwright): no console error, every map
a decoded picture, the hidden variants not on the page.  A screenshot is saved in
tests/artifacts/."""

from __future__ import annotations

import csv
import os
import subprocess
import sys
from pathlib import Path

ARTIFACTS = Path(__file__).resolve().parent.parent / "artifacts"

COMPETITION = """\
name: cup
description: two shipped brains in hidden variants of the yellow arena
scenarios:
  worlds: [DM-USAR_yellow]
  variants: 2
  secret: env:CUP_TEST_SECRET
  seeds: [1]
team: P2AT
duration: 6
teams:
  - name: frontier
    controller: {brain: usarsim.brains.frontier:FrontierExplorer, params: {bounds: auto}}
  - name: wander
    controller: usarsim.brains.wander:Wander
"""


def test_a_competition_runs_and_its_leaderboard_page_opens(browser, tmp_path):
    from usarsim.compete.competition import load_competition

    (tmp_path / "cup.yaml").write_text(COMPETITION)
    env = dict(os.environ, CUP_TEST_SECRET="kept-by-the-organisers")
    out = subprocess.run(
        [sys.executable, "-m", "usarsim", "compete", "cup.yaml", "--workers", "2", "--no-progress"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert out.returncode == 0, out.stdout[-2000:] + out.stderr[-3000:]
    assert "(variants hidden)" in out.stdout and "leaderboard" in out.stdout
    folder = tmp_path / "results" / "cup"
    with open(folder / "leaderboard.csv", newline="") as f:
        board = list(csv.DictReader(f))
    assert [r["rank"] for r in board] == ["1", "2"] and {r["team"] for r in board} == {"frontier", "wander"}
    assert float(board[0]["total"]) >= float(board[1]["total"])
    frontier = next(r for r in board if r["team"] == "frontier")
    assert float(frontier["map_coverage"]) > 0.02 and float(frontier["map_accuracy"]) > 0.5  # it handed a map in
    assert next(r for r in board if r["team"] == "wander")["map_coverage"] == ""  # no map: no map score
    import pyarrow.parquet as pq

    assert pq.read_table(folder / "leaderboard.parquet").num_rows == 2
    with open(folder / "scenarios.csv", newline="") as f:
        assert list(csv.DictReader(f))[0].keys() == {"team", "S1", "S2"}

    os.environ["CUP_TEST_SECRET"] = "kept-by-the-organisers"
    try:
        variants = {s.variant for s in load_competition(tmp_path / "cup.yaml", folder).scenarios}
    finally:
        del os.environ["CUP_TEST_SECRET"]
    html = (folder / "leaderboard.html").read_text()
    assert not any(f"variant {v}" in html for v in variants) and "hidden" in html

    context = browser.new_context(viewport={"width": 1280, "height": 900})
    page = context.new_page()
    errors: list[str] = []
    page.on("console", lambda m: errors.append(f"console.{m.type}: {m.text}") if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(f"uncaught: {e}"))
    try:
        page.goto((folder / "leaderboard.html").as_uri())
        page.wait_for_load_state("load")
        images = page.eval_on_selector_all(
            "img", "imgs => imgs.map(i => [i.alt, i.complete && i.naturalWidth > 0 && i.naturalHeight > 0])"
        )
        # per scenario: its ground truth and each team's map over it
        assert len(images) == 2 * 3 and all(ok for _, ok in images), images
        ranking = page.eval_on_selector_all("table:first-of-type tr td.name", "tds => tds.map(t => t.textContent)")
        assert ranking == [r["team"] for r in board]
        ARTIFACTS.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / "leaderboard.png"), full_page=True)
    finally:
        context.close()
    assert errors == []
