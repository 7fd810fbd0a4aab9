"""A competition's leaderboard: each team's points over the scenario set, with 95 % confidence
intervals over the scenarios, as CSV and Parquet and a self-contained HTML page that shows each
run's map beside the ground truth.

A run's points are the competition's ``points`` of its row (usarsim.compete.competition.Points);
a scenario played with several simulator seeds counts the mean of its runs.  A team's total is
the sum over the scenarios, its mean the mean over them with Student's t interval
(usarsim.sweep.stats.t_interval); a failed run scores 0 and is counted as failed.
"""

from __future__ import annotations

import base64
import html
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from usarsim.compete.competition import Competition, Scenario
from usarsim.sweep.stats import t_interval

LEADERBOARD_COLUMNS = (
    ("rank", "int64"),
    ("team", "string"),
    ("total", "float64"),
    ("mean", "float64"),
    ("ci_low", "float64"),
    ("ci_high", "float64"),
    ("scenarios", "int64"),
    ("failed", "int64"),
    ("victims_found", "float64"),
    ("area_m2", "float64"),
    ("map_coverage", "float64"),
    ("map_accuracy", "float64"),
    ("map_victims", "float64"),
)


@dataclass
class TeamResult:
    """A team's points per scenario (by label) and the rows of its runs."""

    team: str
    per_scenario: dict[str, float | None] = field(default_factory=dict)  # scenario label -> points
    rows: list[dict[str, Any]] = field(default_factory=list)

    def summary(self) -> dict[str, Any]:
        values = [0.0 if v is None else v for v in self.per_scenario.values()]
        ci = t_interval(values)
        good = [r for r in self.rows if not r.get("error")]

        def mean(key: str) -> float | None:
            xs = [float(r[key]) for r in good if r.get(key) is not None]
            return round(sum(xs) / len(xs), 4) if xs else None

        return {
            "team": self.team,
            "total": round(sum(values), 3),
            "mean": round(sum(values) / len(values), 3) if values else None,
            "ci_low": None if ci is None else round(ci[0], 3),
            "ci_high": None if ci is None else round(ci[1], 3),
            "scenarios": len(values),
            "failed": sum(1 for r in self.rows if r.get("error")),
            "victims_found": mean("victims_found"),
            "area_m2": mean("area_m2"),
            "map_coverage": mean("map_coverage"),
            "map_accuracy": mean("map_accuracy"),
            "map_victims": mean("map_victims"),
        }


def tally(comp: Competition, rows: list[dict[str, Any]]) -> list[TeamResult]:
    """Each team's points per scenario, the best team first."""
    by_id = {r["run_id"]: r for r in rows}
    teams = {t: TeamResult(t) for t in comp.teams}
    runs_of: dict[tuple[str, str], list[float | None]] = {}
    for run in comp.runs:
        row = by_id.get(run.run_id)
        team = teams[run.controller.label]
        s = comp.scenario_of(run)
        if row is None:
            continue
        team.rows.append(row)
        runs_of.setdefault((team.team, scenario_key(s)), []).append(comp.points.of(row))
    for t in teams.values():
        for s in comp.scenarios:
            got = runs_of.get((t.team, scenario_key(s)))
            if got is not None and s.label not in t.per_scenario:
                vals = [0.0 if v is None else v for v in got]
                t.per_scenario[s.label] = sum(vals) / len(vals)
    return sorted(teams.values(), key=lambda t: -sum(v or 0.0 for v in t.per_scenario.values()))


def scenario_key(s: Scenario) -> str:
    return f"{s.world}|{s.variant}|{s.seed}"


def leaderboard_rows(results: list[TeamResult]) -> list[dict[str, Any]]:
    out = []
    for rank, t in enumerate(results, 1):
        out.append({"rank": rank, **t.summary()})
    return out


def write_leaderboard(comp: Competition, rows: list[dict[str, Any]], folder: str | Path) -> Path:
    """``leaderboard.csv``, ``leaderboard.parquet``, ``scenarios.csv`` and ``leaderboard.html`` in
    ``folder``; the HTML page's path."""
    import pyarrow as pa
    import pyarrow.csv as pcsv
    import pyarrow.parquet as pq

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    results = tally(comp, rows)
    board = leaderboard_rows(results)
    schema = pa.schema([(n, getattr(pa, k)()) for n, k in LEADERBOARD_COLUMNS])
    table = pa.Table.from_pylist([{n: r.get(n) for n, _ in LEADERBOARD_COLUMNS} for r in board], schema=schema)
    pq.write_table(table, str(folder / "leaderboard.parquet"))
    pcsv.write_csv(table, str(folder / "leaderboard.csv"))
    per = [{"team": t.team, **{s.label: _round(t.per_scenario.get(s.label)) for s in comp.scenarios}} for t in results]
    scen_schema = pa.schema([("team", pa.string()), *((s.label, pa.float64()) for s in comp.scenarios)])
    pcsv.write_csv(pa.Table.from_pylist(per, schema=scen_schema), str(folder / "scenarios.csv"))
    draw_truths(comp, folder / "maps")
    page = folder / "leaderboard.html"
    tmp = folder / ".leaderboard.html.tmp"
    tmp.write_text(leaderboard_html(comp, results, board, rows, folder / "maps"), encoding="utf-8")
    os.replace(tmp, page)
    return page


def truth_picture(maps: Path, s: Scenario) -> Path:
    return maps / f"truth-{s.label}.png"


def draw_truths(comp: Competition, maps: Path) -> None:
    """A picture of each scenario's ground truth (its world and variant), once."""
    from usarsim.maps.picture import draw_grid
    from usarsim.maps.truth import ground_truth_map
    from usarsim.maps.variation import load_arena

    for s in comp.scenarios:
        path = truth_picture(maps, s)
        if not path.exists():
            world = next(r.world for r in comp.runs if comp.scenario_of(r) == s)
            truth = ground_truth_map(load_arena(world, s.variant), variant=s.variant)
            draw_grid(path, truth.grid, truth.markers)


def _round(v: float | None) -> float | None:
    return None if v is None else round(v, 3)


def _fmt(v: Any, digits: int = 1) -> str:
    if v is None:
        return "–"
    if isinstance(v, float):
        return f"{v:.{digits}f}"
    return html.escape(str(v))


def _png(path: Path) -> str:
    """An <img> of a PNG, inlined (the page stands alone), or a note that there is none."""
    if not path.exists():
        return '<span class="none">no picture</span>'
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return f'<img alt="{html.escape(path.stem)}" src="data:image/png;base64,{data}">'


STYLE = """
body { font-family: system-ui, sans-serif; margin: 2em; color: #222; }
table { border-collapse: collapse; margin: 1em 0; }
th, td { border: 1px solid #ccc; padding: 0.3em 0.6em; text-align: right; }
th { background: #f0f0f4; } td.name { text-align: left; font-weight: 600; }
.maps { display: flex; flex-wrap: wrap; gap: 1em; } .maps figure { margin: 0; }
.maps img { max-width: 420px; border: 1px solid #bbb; } figcaption { font-size: 0.9em; }
.none { color: #888; font-style: italic; } .legend span { margin-right: 1.2em; }
"""


def leaderboard_html(
    comp: Competition, results: list[TeamResult], board: list[dict[str, Any]], rows: list[dict[str, Any]], maps: Path
) -> str:
    """The leaderboard page: the ranking, the points per scenario, each scenario's ground truth
    and every team's map of it."""
    esc = html.escape
    out = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{esc(comp.name)}: leaderboard</title><style>{STYLE}</style></head><body>",
        f"<h1>{esc(comp.name)}</h1>",
    ]
    if comp.description:
        out.append(f"<p>{esc(comp.description)}</p>")
    out.append(
        f"<p>{len(comp.teams)} teams, {len(comp.scenarios)} scenarios; points per run: "
        f"{comp.points.score:g} x score + {comp.points.map:g} x map coverage x accuracy + "
        f"{comp.points.map_victims:g} per victim on the map. Intervals: 95 % over the scenarios.</p>"
    )
    out.append("<h2>Ranking</h2><table><tr>")
    heads = ["Rank", "Team", "Total", "Mean", "95 % CI", "Failed", "Victims", "Area m²", "Map coverage", "Map accuracy"]
    out += [f"<th>{h}</th>" for h in heads] + ["</tr>"]
    for r in board:
        ci = "–" if r["ci_low"] is None else f"{r['ci_low']:.1f} – {r['ci_high']:.1f}"
        cov = "–" if r["map_coverage"] is None else f"{100 * r['map_coverage']:.1f} %"
        acc = "–" if r["map_accuracy"] is None else f"{100 * r['map_accuracy']:.1f} %"
        out.append(
            f"<tr><td>{r['rank']}</td><td class='name'>{esc(r['team'])}</td><td>{_fmt(r['total'])}</td>"
            f"<td>{_fmt(r['mean'])}</td><td>{ci}</td><td>{r['failed']}</td><td>{_fmt(r['victims_found'], 2)}</td>"
            f"<td>{_fmt(r['area_m2'])}</td><td>{cov}</td><td>{acc}</td></tr>"
        )
    out.append("</table><h2>Points per scenario</h2><table><tr><th>Team</th>")
    for s in comp.scenarios:
        variant = "as written" if s.variant is None else ("hidden" if comp.hidden else f"variant {s.variant}")
        out.append(f"<th>{s.label}<br><small>{esc(s.world)}<br>{variant}, seed {s.seed}</small></th>")
    out.append("</tr>")
    for t in results:
        cells = "".join(f"<td>{_fmt(t.per_scenario.get(s.label))}</td>" for s in comp.scenarios)
        out.append(f"<tr><td class='name'>{esc(t.team)}</td>{cells}</tr>")
    out.append("</table><h2>Maps</h2>")
    out.append(
        "<p class='legend'><span>grey: the ground truth's walls</span><span>green: floor the team mapped</span>"
        "<span>red: walls the team mapped</span><span>red crosses: victims the team put on its map</span>"
        "<span>red discs: victims, blue squares: RFID tags, green triangles: start poses</span></p>"
    )
    by_id = {r["run_id"]: r for r in rows}
    for s in comp.scenarios:
        out.append(f"<h3>{s.label}: {esc(s.world)}</h3><div class='maps'>")
        out.append(f"<figure>{_png(truth_picture(maps, s))}<figcaption><b>ground truth</b></figcaption></figure>")
        for run in comp.runs:
            if comp.scenario_of(run) != s:
                continue
            row = by_id.get(run.run_id) or {}
            coverage, accuracy = row.get("map_coverage"), row.get("map_accuracy")
            if coverage is not None and accuracy is not None:
                what = f"coverage {100 * coverage:.0f} %, accuracy {100 * accuracy:.0f} %"
            elif row.get("error"):
                what = "failed: " + esc(str(row["error"])[:160])
            else:
                what = "no map handed in"
            out.append(
                f"<figure>{_png(maps / f'{run.run_id}.png')}<figcaption><b>{esc(run.controller.label)}</b>: "
                f"{what}</figcaption></figure>"
            )
        out.append("</div>")
    out.append("</body></html>")
    return "\n".join(out) + "\n"
