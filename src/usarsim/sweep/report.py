"""The report of a sweep: per configuration (the runs that differ only in their seed), the
mean, standard deviation and 95 % confidence interval of every score (each score's interval
by a method suited to it: :mod:`usarsim.sweep.stats`); plots of the score, the victims found
and the area explored against the sweep's axes; and one self-contained HTML page with both
(the plots embedded as data URIs), ``report.html`` beside the results.

Everywhere (terminal, page, plots) a score reads ``mean [low, high]``: its mean over the
seeds and the 95 % confidence interval of that mean.
"""

from __future__ import annotations

import base64
import html
import io
import math
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, cast

from usarsim.sweep.experiment import CONFIG_COLUMNS, varying_axes
from usarsim.sweep.results import SCORE_COLUMNS, read_rows
from usarsim.sweep.stats import METHOD_NAMES, POISSON, T_CLIPPED, T, poisson_interval, t975, t_interval

__all__ = ["INTERVALS", "METRICS", "Group", "Stat", "build_report", "summarize", "t975"]

# The scores the summary gives, with their names for people.
METRICS = {
    "score": "score",
    "victims_found": "victims found",
    "victims_reported": "victims reported",
    "false_reports": "false reports",
    "area_m2": "area explored (m²)",
    "distance_m": "distance (m)",
    "collisions": "collisions",
    "robots_lost": "robots lost",
    "radio_contact_share": "radio contact share",
    "messages_delivered": "team messages delivered",
    "messages_lost": "team messages lost",
}
PLOTTED = ("score", "victims_found", "area_m2")
AXIS_NAMES = {
    "world": "world",
    "variant": "world variant",
    "team": "team",
    "wireless": "wireless model",
    "duration_s": "duration (s)",
    "clock": "clock",
    "controller": "controller",
}

# Each score's 95 % interval: its method and the range its mean can take (docs/experiments.md).
# Robots lost are also at most the team's size.
INTERVALS: dict[str, tuple[str, float | None, float | None]] = {
    "score": (T, None, None),  # penalties make it negative: any number
    "victims_found": (POISSON, 0.0, None),
    "victims_reported": (POISSON, 0.0, None),
    "false_reports": (POISSON, 0.0, None),
    "collisions": (POISSON, 0.0, None),
    "robots_lost": (POISSON, 0.0, None),
    "area_m2": (T_CLIPPED, 0.0, None),
    "distance_m": (T_CLIPPED, 0.0, None),
    "radio_contact_share": (T_CLIPPED, 0.0, 1.0),
    "messages_delivered": (POISSON, 0.0, None),
    "messages_lost": (POISSON, 0.0, None),
}


def method_of(metric: str) -> str:
    """How ``metric``'s interval is made, for people: "exact Poisson (Garwood)"..."""
    method, low, high = INTERVALS.get(metric, (T, None, None))
    if method != T_CLIPPED:
        return METHOD_NAMES[method]
    return "Student's t, clipped at 0" if high is None else f"Student's t, clipped to [{low:g}, {high:g}]"


@dataclass
class Stat:
    """Mean, sample standard deviation (None for fewer than two values) and the 95 %
    confidence interval of the mean by ``method`` (None where it has too few values: a t
    interval needs two, a Poisson one a single count)."""

    n: int
    mean: float | None
    sd: float | None
    ci_low: float | None
    ci_high: float | None
    method: str = T

    @classmethod
    def of(cls, values: list[float], metric: str | None = None, team_size: int | None = None) -> Stat:
        """The statistics of ``values``; the interval ``metric``'s (INTERVALS; Student's t
        when None), robots lost clipped at ``team_size``."""
        method, low, high = INTERVALS.get(metric, (T, None, None)) if metric else (T, None, None)
        n = len(values)
        if n == 0:
            return cls(0, None, None, None, None, method)
        mean = sum(values) / n
        sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1)) if n > 1 else None
        if method == POISSON:
            ci = poisson_interval(values, high=team_size if metric == "robots_lost" else None)
        else:
            ci = t_interval(values, low, high)
        ci_low, ci_high = ci or (None, None)
        return cls(n, mean, sd, ci_low, ci_high, method)


@dataclass
class Group:
    """The runs of one configuration."""

    config: dict[str, Any]
    seeds: list[int] = field(default_factory=list)
    failed: int = 0
    values: dict[str, list[float]] = field(default_factory=dict)
    team_size: int | None = None

    def stat(self, metric: str) -> Stat:
        return Stat.of(self.values.get(metric, []), metric, self.team_size)


def summarize(rows: list[dict[str, Any]]) -> list[Group]:
    """The configurations of ``rows`` in the order they first appear, each with the scores
    of its successful runs (a failed run is counted, never averaged)."""
    groups: dict[tuple, Group] = {}
    for r in rows:
        key = tuple(r.get(c) for c in CONFIG_COLUMNS)
        g = groups.setdefault(key, Group({c: r.get(c) for c in CONFIG_COLUMNS}))
        if r.get("robots_n") is not None:
            g.team_size = max(g.team_size or 0, int(r["robots_n"]))
        if r.get("error"):
            g.failed += 1
            continue
        g.seeds.append(cast(int, r.get("seed")))  # every run has its seed (Run.seed)
        for m in METRICS:
            v = r.get(m)
            if v is not None and not (isinstance(v, float) and math.isnan(v)):
                g.values.setdefault(m, []).append(float(v))
    return list(groups.values())


def short(value: Any, limit: int = 32) -> str:
    """A configuration value as a label: a world file by its name, long texts cut."""
    text = f"{value:g}" if isinstance(value, float) else str(value)
    if "/" in text and text.endswith((".yaml", ".yml")):
        text = Path(text).stem
    return text if len(text) <= limit else text[: limit - 1] + "…"


def fmt(v: float | None, digits: int = 1) -> str:
    if v is None:
        return "–"
    return f"{v:.{digits}f}" if abs(v) < 1e6 else f"{v:.3g}"


def fmt_ci(s: Stat, digits: int = 1) -> str:
    """``[low, high]``, the interval of ``s`` (empty where it has none)."""
    return f"[{fmt(s.ci_low, digits)}, {fmt(s.ci_high, digits)}]" if s.ci_low is not None else ""


def fmt_stat(s: Stat, digits: int = 1) -> str:
    """``mean [low, high]``: the mean and its 95 % confidence interval."""
    ci = fmt_ci(s, digits)
    return fmt(s.mean, digits) + (f" {ci}" if ci else "")


def digits_of(metric: str) -> int:
    """The decimals ``metric`` is shown with."""
    return (
        3
        if metric == "radio_contact_share"
        else 2
        if metric
        in (
            "collisions",
            "robots_lost",
            "victims_found",
            "victims_reported",
            "false_reports",
            "messages_delivered",
            "messages_lost",
        )
        else 1
    )


# ---------------------------------------------------------------- plots


def plot(rows: list[dict[str, Any]], metric: str, axis: str | None, axes: tuple[str, ...]) -> bytes:
    """A PNG: the mean of ``metric`` with its 95 % interval against the values of ``axis``
    (None: every configuration in one group), one series per combination of the other
    axes, each run a faint dot."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [r for r in rows if not r.get("error") and r.get(metric) is not None]
    others = [a for a in axes if a != axis]
    xs = _ordered([r.get(axis) for r in ok] if axis else ["all runs"])
    series = _ordered([tuple(r.get(a) for a in others) for r in ok]) or [()]
    fig, ax = plt.subplots(figsize=(6.0, 3.8), dpi=100)
    width = 0.7 / max(1, len(series))
    for si, combo in enumerate(series):
        offset = (si - (len(series) - 1) / 2) * width
        label = ", ".join(short(v, 24) for v in combo) if combo else None
        mx, my, lo, hi = [], [], [], []
        for xi, x in enumerate(xs):
            sel = [r for r in ok if (axis is None or r.get(axis) == x) and tuple(r.get(a) for a in others) == combo]
            if not sel:
                continue
            vals = [float(r[metric]) for r in sel]
            sizes = [int(r["robots_n"]) for r in sel if r.get("robots_n") is not None]
            s = Stat.of(vals, metric, max(sizes) if sizes else None)
            mean = s.mean
            assert mean is not None  # sel is not empty
            mx.append(xi + offset)
            my.append(mean)
            lo.append(mean - (s.ci_low if s.ci_low is not None else mean))
            hi.append((s.ci_high if s.ci_high is not None else mean) - mean)
            ax.scatter([xi + offset] * len(vals), vals, s=12, alpha=0.35, color=f"C{si % 10}", zorder=2)
        ax.errorbar(mx, my, yerr=[lo, hi], fmt="o", capsize=4, color=f"C{si % 10}", label=label, zorder=3)
    ax.set_xticks(range(len(xs)))
    ax.set_xticklabels(
        [short(x, 28) for x in xs], rotation=15 if len(xs) > 3 else 0, ha="right" if len(xs) > 3 else "center"
    )
    ax.set_xlim(-0.6, len(xs) - 0.4)
    ax.set_xlabel(AXIS_NAMES.get(axis, axis) if axis else "")
    ax.set_ylabel(METRICS[metric])
    ax.set_title(
        f"{METRICS[metric]}"
        + (f" by {AXIS_NAMES.get(axis, axis)}" if axis else "")
        + f"\nmean, 95 % CI ({method_of(metric)}); dots: runs",
        fontsize=10,
    )
    ax.grid(axis="y", alpha=0.3)
    if len(series) > 1:
        ax.legend(title=", ".join(AXIS_NAMES.get(a, a) for a in others), fontsize=8, title_fontsize=8)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    plt.close(fig)
    return buf.getvalue()


def _ordered(values: list) -> list:
    """The distinct values in the order they first appear (numbers sorted)."""
    distinct = list(dict.fromkeys(values))
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in distinct):
        return sorted(distinct)
    return distinct


# ---------------------------------------------------------------- the report


@dataclass
class Report:
    folder: Path
    html_path: Path
    summary_csv: Path
    plots: list[Path]
    groups: list[Group]
    axes: tuple[str, ...]
    rows: list[dict[str, Any]]


def build_report(folder: str | Path) -> Report:
    """Write ``summary.csv``, the plots (``plot-<score>-by-<axis>.png``) and ``report.html``
    into the results folder ``folder``."""
    folder = Path(folder)
    rows = read_rows(folder)
    groups = summarize(rows)
    axes = varying_axes(rows)
    summary_csv = folder / "summary.csv"
    _write_summary_csv(groups, summary_csv)
    plots: list[tuple[Path, str, bytes]] = []
    for metric in PLOTTED:
        for axis in axes or (None,):
            png = plot(rows, metric, axis, axes)
            name = f"plot-{metric}" + (f"-by-{axis}" if axis else "") + ".png"
            caption = METRICS[metric] + (f" by {AXIS_NAMES.get(axis, axis)}" if axis else "")
            (folder / name).write_bytes(png)
            plots.append((folder / name, caption, png))
    html_path = folder / "report.html"
    html_path.write_text(_html(folder, rows, groups, axes, plots), encoding="utf-8")
    return Report(folder, html_path, summary_csv, [p for p, _, _ in plots], groups, axes, rows)


def _write_summary_csv(groups: list[Group], path: Path) -> None:
    import csv

    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        header = [*CONFIG_COLUMNS, "runs", "failed", "seeds"]
        for m in SCORE_COLUMNS:
            header += [f"{m}_mean", f"{m}_sd", f"{m}_ci95_low", f"{m}_ci95_high"]
        w.writerow(header)
        for g in groups:
            line = [g.config[c] for c in CONFIG_COLUMNS] + [len(g.seeds), g.failed, " ".join(map(str, sorted(g.seeds)))]
            for m in SCORE_COLUMNS:
                s = g.stat(m)
                line += ["" if v is None else round(v, 6) for v in (s.mean, s.sd, s.ci_low, s.ci_high)]
            w.writerow(line)


_CSS = """
body { font: 14px/1.45 system-ui, -apple-system, 'Segoe UI', sans-serif; margin: 1.5em auto; max-width: 1280px;
       padding: 0 1em; color: #1d2330; box-sizing: border-box; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; } h2 { font-size: 1.2em; margin-top: 1.6em; }
.meta { color: #5a6375; }
.fit { max-width: 100%; overflow-x: auto; }
table { border-collapse: collapse; margin: 0.5em 0; font-variant-numeric: tabular-nums; font-size: 13px; }
th, td { border: 1px solid #d5dae3; padding: 0.25em 0.4em; text-align: left; vertical-align: top; }
th { background: #eef1f6; font-weight: 600; } th .how { display: block; font-weight: normal; font-size: 0.85em;
     color: #5a6375; }
td.num { text-align: right; white-space: nowrap; }
td.cfg { max-width: 16em; overflow-wrap: break-word; } td.word { white-space: nowrap; }
td .ci { display: block; color: #6b7385; font-size: 0.85em; }
.plots { display: flex; flex-wrap: wrap; gap: 1em; }
figure { margin: 0; border: 1px solid #d5dae3; padding: 0.5em; background: #fff; max-width: 100%;
         box-sizing: border-box; }
figure img { display: block; max-width: 100%; height: auto; }
figcaption { color: #5a6375; font-size: 0.9em; margin-top: 0.3em; }
td.err { font-family: ui-monospace, monospace; font-size: 0.85em; white-space: pre-wrap; overflow-wrap: anywhere;
         max-width: 60em; }
"""

# Each interval method as a column's header says it.
_HOW = {"score": "t", "area_m2": "t, ≥ 0", "distance_m": "t, ≥ 0", "radio_contact_share": "t, 0 to 1"}


def _how(metric: str) -> str:
    return _HOW.get(metric, "Poisson" if INTERVALS[metric][0] == POISSON else "t")


def _cfg_cell(text: str) -> str:
    """A configuration's value; a short one in a word (a world's name) kept on one line."""
    whole = " " not in text and len(text) <= 24
    return f'<td class="cfg{" word" if whole else ""}">{html.escape(text)}</td>'


# Scores a run has only with a radio channel beyond USARSim's (docs/wireless.md): the summary
# shows them when some run counted a message
CHANNEL_SCORES = ("messages_delivered", "messages_lost")


def shown_metrics(rows: list[dict[str, Any]]) -> list[str]:
    """The scores the summary table shows: every one, but the channel's messages only when some
    run counted one."""
    counted = any((r.get(m) or 0) > 0 for r in rows for m in CHANNEL_SCORES)
    return [m for m in SCORE_COLUMNS if counted or m not in CHANNEL_SCORES]


def _html(
    folder: Path,
    rows: list[dict[str, Any]],
    groups: list[Group],
    axes: tuple[str, ...],
    plots: list[tuple[Path, str, bytes]],
) -> str:
    e = html.escape
    names = sorted({str(r.get("experiment")) for r in rows}) or [folder.name]
    failed = [r for r in rows if r.get("error")]
    seeds = sorted({r["seed"] for r in rows if r.get("seed") is not None})
    shown = [c for c in CONFIG_COLUMNS if c in axes] or list(CONFIG_COLUMNS)
    fixed = [c for c in CONFIG_COLUMNS if c not in shown]
    out = [
        "<!doctype html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        '<link rel="icon" href="data:,">',
        f"<title>usarsim sweep report: {e(', '.join(names))}</title>",
        f"<style>{_CSS}</style></head><body>",
        f"<h1>Sweep report: {e(', '.join(names))}</h1>",
        f'<p class="meta">{len(rows)} runs ({len(failed)} failed) in {len(groups)} configurations; seeds '
        f"{e(', '.join(map(str, seeds)))}; written {datetime.now(UTC).strftime('%Y-%m-%d %H:%M UTC')} "
        f"from {e(str(folder.resolve() / 'results.parquet'))}</p>",
    ]
    if fixed and rows:
        first = rows[0]
        out.append(
            '<p class="meta">Every run: '
            + "; ".join(f"{e(AXIS_NAMES[c])}: {e(short(first.get(c), 80))}" for c in fixed)
            + "</p>"
        )
    out.append("<h2>Summary</h2>")
    out.append(
        '<p class="meta" id="how">Per configuration, over its seeds: the mean, and under it '
        "[low, high], the 95 % confidence interval of the mean (the standard deviation shows when the "
        "pointer rests on a cell). Intervals: <b>t</b>: Student's t; <b>t, ≥ 0</b> and <b>t, 0 to 1</b>: "
        "Student's t clipped to the range the score can take; <b>Poisson</b>: the exact Poisson interval "
        "(Garwood) of a count per run (robots lost also at most the team's size). Failed runs are counted, "
        "not averaged.</p>"
    )
    out.append('<div class="fit"><table id="summary"><thead><tr>')
    out += [f"<th>{e(AXIS_NAMES[c])}</th>" for c in shown]
    metrics = shown_metrics(rows)
    out += ["<th>runs</th>", "<th>failed</th>"] + [
        f'<th>{e(METRICS[m])}<span class="how">mean [95 % CI, {e(_how(m))}]</span></th>' for m in metrics
    ]
    out.append("</tr></thead><tbody>")
    for g in groups:
        out.append("<tr>" + "".join(_cfg_cell(short(g.config[c], 60)) for c in shown))
        out.append(f'<td class="num">{len(g.seeds)}</td><td class="num">{g.failed}</td>')
        for m in metrics:
            s, d = g.stat(m), digits_of(m)
            tip = f' title="standard deviation {fmt(s.sd, d)} over {s.n} runs"' if s.sd is not None else ""
            ci = f'<span class="ci">{fmt_ci(s, d)}</span>' if s.ci_low is not None else ""
            out.append(f'<td class="num"{tip}>{fmt(s.mean, d)}{ci}</td>')
        out.append("</tr>")
    out.append("</tbody></table></div>")
    out.append('<h2>Plots</h2><div class="plots">')
    for path, caption, png in plots:
        data = base64.b64encode(png).decode("ascii")
        out.append(
            f'<figure><img src="data:image/png;base64,{data}" alt="{e(caption)}">'
            f"<figcaption>{e(caption)} ({e(path.name)})</figcaption></figure>"
        )
    out.append("</div>")
    if failed:
        out.append(
            '<h2>Failed runs</h2><table id="failed"><thead><tr><th>run</th><th>world</th><th>seed</th>'
            "<th>controller</th><th>error</th></tr></thead><tbody>"
        )
        for r in failed:
            out.append(
                f"<tr><td>{e(str(r.get('run_id')))}</td><td>{e(short(r.get('world')))}</td>"
                f"<td>{e(str(r.get('seed')))}</td><td>{e(short(r.get('controller'), 60))}</td>"
                f'<td class="err">{e(str(r.get("error")))}</td></tr>'
            )
        out.append("</tbody></table>")
    out.append("</body></html>")
    return "\n".join(out)
