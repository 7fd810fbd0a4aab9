"""The sweep report's HTML page (usarsim report) in a real headless browser (Chromium
through Playwright): it opens from the file alone with no console error, every plot is a
decoded picture, the summary table has a row per configuration, says in each score's header
what its cells are (mean [95 % CI, method]), and the page fits a 1280 px wide window, its
summary table included.  A screenshot of the page is saved in tests/artifacts/."""

from __future__ import annotations

from pathlib import Path

from usarsim.sweep.report import build_report
from usarsim.sweep.results import write_rows

ARTIFACTS = Path(__file__).resolve().parent.parent / "artifacts"


def sweep_rows() -> list[dict]:
    """A sweep of 2 worlds x 2 teams x 3 seeds, with one failed run."""
    rows = []
    for world, base in (("DM-USAR_yellow", 120.0), ("DM-USAR_red", 80.0)):
        for team, gain in (("P2AT", 0.0), ("2xP2AT", 45.0)):
            for seed, noise in zip((1, 2, 3), (-6.0, 1.0, 5.0)):
                area = base + gain + noise
                victims = (seed + len(team)) % 3
                rows.append(
                    {
                        "run_id": f"{world}-{team}-{seed}",
                        "experiment": "page",
                        "world": world,
                        "seed": seed,
                        "team": team,
                        "robots_n": 2 if team.startswith("2x") else 1,
                        "wireless": "world",
                        "duration_s": 60.0,
                        "clock": "lockstep",
                        "controller": "FrontierExplorer",
                        "score": area + 50.0 * victims,
                        "victims_found": victims,
                        "victims_reported": 0,
                        "false_reports": 0,
                        "area_m2": area,
                        "distance_m": 12.0 + noise,
                        "collisions": seed % 2,
                        "robots_lost": 0,
                        "radio_contact_share": 0.5 if team.startswith("2x") else 0.0,
                        "time_s": 60.2,
                        "wall_s": 4.0,
                        "error": None,
                        "log": "",
                    }
                )
    rows.append(
        dict(
            rows[0],
            run_id="lost",
            seed=4,
            score=None,
            area_m2=None,
            error="the controller exited with code 1: <no map>",
            log="usarsim: ...",
        )
    )
    return rows


def test_the_report_page_opens_without_errors_and_shows_its_plots(browser, tmp_path):
    write_rows(sweep_rows(), tmp_path)
    report = build_report(tmp_path)
    assert len(report.plots) == 6  # score, victims, area by world and by team
    context = browser.new_context(viewport={"width": 1280, "height": 900})
    page = context.new_page()
    errors: list[str] = []
    page.on("console", lambda m: errors.append(f"console.{m.type}: {m.text}") if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(f"uncaught: {e}"))
    failed_requests: list[str] = []
    page.on("requestfailed", lambda r: failed_requests.append(r.url[:80]))
    try:
        page.goto(report.html_path.as_uri())
        page.wait_for_load_state("load")
        images = page.eval_on_selector_all(
            "figure img",
            "els => els.map(e => ({w: e.naturalWidth, h: e.naturalHeight, done: e.complete,"
            " src: e.getAttribute('src').slice(0, 22)}))",
        )
        assert len(images) == 6
        for img in images:
            assert img["done"] and img["w"] > 0 and img["h"] > 0, img
            assert img["src"] == "data:image/png;base64,"  # embedded: the page needs no other file
        assert page.eval_on_selector_all("#summary tbody tr", "rows => rows.length") == 4
        headers = page.eval_on_selector_all("#summary thead th", "els => els.map(e => e.textContent)")
        assert (
            headers[:4] == ["world", "team", "runs", "failed"] and "area explored (m²)mean [95 % CI, t, ≥ 0]" in headers
        )
        assert "victims foundmean [95 % CI, Poisson]" in headers and "scoremean [95 % CI, t]" in headers
        assert "±" not in page.text_content("body")  # one notation: mean, then [low, high]
        # a count's interval never goes below 0 (victims 0, 1, 2 of team P2AT at DM-USAR_yellow)
        assert page.text_content("#summary tbody tr:first-child td:nth-child(6)") == "1.00[0.21, 2.92]"
        assert fits_1280(page)
        assert "the controller exited with code 1: <no map>" in page.text_content("#failed")
        assert page.title() == "usarsim sweep report: page"
        ARTIFACTS.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / "report-page.png"), full_page=True)
    finally:
        context.close()
    assert errors == [] and failed_requests == []


def fits_1280(page) -> bool:
    """The page, and its summary table, no wider than the 1280 px window (no sideways scroll)."""
    width = page.evaluate("document.documentElement.scrollWidth")
    table = page.evaluate(
        "(() => { const t = document.getElementById('summary');"
        " return [t.getBoundingClientRect().right, t.parentElement.scrollWidth,"
        " t.parentElement.clientWidth]; })()"
    )
    assert width <= 1280, f"the page is {width} px wide"
    assert table[0] <= 1280 and table[1] <= table[2], f"the summary table overflows: {table}"
    return True


def test_a_report_of_three_axes_with_long_labels_fits_1280_px(browser, tmp_path):
    rows = sweep_rows()
    rows += [
        dict(r, run_id=f"{r['run_id']}-tuned", controller='FrontierExplorer(bounds="auto", speed=0.4, turn_rate=0.8)')
        for r in rows
    ]
    write_rows(rows, tmp_path)
    report = build_report(tmp_path)
    assert report.axes == ("world", "team", "controller")
    context = browser.new_context(viewport={"width": 1280, "height": 900})
    page = context.new_page()
    try:
        page.goto(report.html_path.as_uri())
        page.wait_for_load_state("load")
        assert page.eval_on_selector_all("#summary tbody tr", "rows => rows.length") == 8
        assert fits_1280(page)
    finally:
        context.close()
