"""Sweeps (usarsim.sweep) end to end: the experiment file's checks, the list of runs, real
sweeps on a local Ray with real simulators scoring every run (serve --score-file), the
results store that skips what is done, failed runs recorded with their errors, and the
report's statistics.  One Ray is started for the whole module."""

from __future__ import annotations

import csv
import json
import math
import sys
from pathlib import Path

import pytest

from usarsim.errors import ConfigError
from usarsim.sweep.cli import main
from usarsim.sweep.experiment import load_experiment
from usarsim.sweep.report import Stat, build_report, summarize, t975
from usarsim.sweep.results import read_rows, write_rows
from usarsim.sweep.runner import run_sweep

TWO_BY_TWO = """\
name: two-by-two
seeds: [1, 2]
team: P2AT
duration: 12
clock: lockstep
controller: {brain: usarsim.brains.frontier:FrontierExplorer, params: {bounds: auto}}
grid:
  world: [DM-USAR_yellow, DM-USAR_red]
"""


def write(folder: Path, text: str, name: str = "experiment.yaml") -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def local_ray():
    """One local Ray of two CPUs for the module (sweeps started here reuse it)."""
    pytest.importorskip("ray")
    import ray

    from usarsim.sweep.runner import start_ray

    assert start_ray(2, None)
    yield
    ray.shutdown()


# ---------------------------------------------------------------- the experiment file


def error_of(tmp_path: Path, text: str) -> ConfigError:
    path = write(tmp_path, text)
    with pytest.raises(ConfigError) as info:
        load_experiment(path)
    assert str(path) in str(info.value)  # every error names the file
    return info.value


def test_a_misspelt_key_is_named_with_the_key_it_resembles(tmp_path):
    err = error_of(tmp_path, "wrld: DM-USAR_yellow\nseeds: [1]\n")
    assert err.key == "wrld"
    assert "unknown key 'wrld' (did you mean 'world'?)" in str(err)
    assert "allowed: clock, controller, description, duration, grid" in str(err)
    err = error_of(tmp_path, "grid:\n  wordl: [DM-USAR_yellow, DM-USAR_red]\n")
    assert err.key == "grid.wordl" and "(did you mean 'world'?)" in str(err)
    err = error_of(tmp_path, "runs:\n  - {world: DM-USAR_red, seed: 3}\n")
    assert err.key == "runs[0].seed" and "(did you mean 'seeds'?)" in str(err)


def test_an_unknown_world_is_named_with_the_closest_shipped_world(tmp_path):
    err = error_of(tmp_path, "grid:\n  world: [DM-USAR_yellow, DM-USAR_rde]\n")
    assert err.key == "grid.world[1]"
    assert "unknown world 'DM-USAR_rde' (did you mean 'DM-USAR_red'?)" in str(err)
    assert "DM-USAR_orange" in str(err)  # and what is allowed
    err = error_of(tmp_path, "world: no/such/world.yaml\n")
    assert err.key == "world" and "no such world file" in str(err)


def test_an_unknown_robot_class_and_start_pose_are_named_with_the_closest(tmp_path):
    err = error_of(tmp_path, "team: [{robot: P2TA, count: 2}]\n")
    assert err.key == "team[0].robot"
    assert "unknown robot class 'P2TA' (did you mean 'P2AT'?)" in str(err)
    err = error_of(tmp_path, "team: [{robot: P2AT, start: PlayerStart9}]\n")
    assert err.key == "team[0].start" and "(did you mean 'PlayerStart8'?)" in str(err)
    err = error_of(tmp_path, "team: {robot: P2AT, count: 9}\n")  # DM-USAR_yellow has 8 start poses
    assert "more robots than world DM-USAR_yellow has start poses (8)" in str(err)


def test_controllers_are_checked_before_anything_runs(tmp_path):
    err = error_of(tmp_path, "controller: usarsim.brains.wander:Wandr\n")
    assert err.key == "controller.brain" and "(did you mean 'Wander'?)" in str(err)
    err = error_of(tmp_path, "controller: {brain: usarsim.brains.wander:Wander, params: {sped: 0.3}}\n")
    assert err.key == "controller.params.sped" and "(did you mean 'speed'?)" in str(err)
    err = error_of(tmp_path, "controller: 'python3 bot.py --host {hots} --port {port}'\n")
    assert "unknown placeholder '{hots}' (did you mean 'host'?)" in str(err)
    err = error_of(tmp_path, "clock: lockstpe\n")
    assert err.key == "clock" and "(did you mean 'lockstep'?)" in str(err)
    err = error_of(tmp_path, "wireless: wap\n")
    assert "(did you mean 'waf'?)" in str(err)


def test_the_command_line_prints_the_error_and_exits_1(tmp_path, capsys):
    path = write(tmp_path, "name: bad\nteam: P2TA\n")
    assert main(["sweep", str(path), "--dry-run"]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"usarsim: error: {path}: team: unknown robot class 'P2TA' (did you mean 'P2AT'?)")


def test_dry_run_lists_every_run_and_runs_none(tmp_path, capsys):
    path = write(
        tmp_path,
        TWO_BY_TWO + "runs:\n  - {world: DM-USAR_orange, team: [{robot: P3AT, count: 2}], seeds: [7], clock: max}\n",
    )
    exp = load_experiment(path)
    assert [(r.world, r.seed, r.team_label, r.clock) for r in exp.runs] == [
        ("DM-USAR_yellow", 1, "P2AT", "lockstep"),
        ("DM-USAR_yellow", 2, "P2AT", "lockstep"),
        ("DM-USAR_red", 1, "P2AT", "lockstep"),
        ("DM-USAR_red", 2, "P2AT", "lockstep"),
        ("DM-USAR_orange", 7, "2xP3AT", "max"),
    ]
    assert [(m.name, m.start) for m in exp.runs[-1].team] == [("R1", "PlayerStart1"), ("R2", "PlayerStart2")]
    assert len({r.run_id for r in exp.runs}) == 5
    assert exp.axes == ("world", "team", "clock")
    out = tmp_path / "out"
    assert main(["sweep", str(path), "--dry-run", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    for r in exp.runs:
        assert r.run_id in text
    assert sum(line.endswith(" new") for line in text.splitlines()) == 5 and "DM-USAR_orange" in text
    assert all(
        line == line.rstrip() for line in text.splitlines()
    )  # no padding at the ends of lines and "2xP3AT" in text
    assert "5 runs: 0 done already" in text and "5 to run" in text
    assert not out.exists()  # nothing ran, nothing written


def test_a_wireless_configuration_file_is_a_value_of_the_wireless_axis(tmp_path):
    from usarsim.sweep.worker import server_arguments

    (tmp_path / "radio.yaml").write_text("channel: {loss: {model: independent, rate: 0.1}}\n")
    exp = load_experiment(write(tmp_path, TWO_BY_TWO.replace("grid:", "wireless: radio.yaml\ngrid:")))
    assert {r.wireless for r in exp.runs} == {str((tmp_path / "radio.yaml").resolve())}
    assert server_arguments(exp.runs[0])[-2:] == ["--wireless-config", str((tmp_path / "radio.yaml").resolve())]
    (tmp_path / "bad.yaml").write_text("channel: {loss: {model: independent, rate: 5}}\n")
    err = error_of(tmp_path, TWO_BY_TWO.replace("grid:", "wireless: bad.yaml\ngrid:"))
    assert "probability" in str(err)
    err = error_of(tmp_path, TWO_BY_TWO.replace("grid:", "wireless: nothere.yaml\ngrid:"))
    assert "nothere.yaml" in str(err)


# ---------------------------------------------------------------- real sweeps


def score_columns(rows):
    keys = ("score", "victims_found", "area_m2", "distance_m", "collisions", "robots_lost", "time_s", "robots")
    return {r["run_id"]: tuple(r[k] for k in keys) for r in rows}


def test_a_two_by_two_sweep_scores_every_run_repeats_identically_and_skips_what_is_done(local_ray, tmp_path, capsys):
    path = write(tmp_path, TWO_BY_TWO)
    exp = load_experiment(path)
    out = tmp_path / "results"
    assert main(["sweep", str(path), "--out", str(out), "--no-progress"]) == 0
    printed = capsys.readouterr().out
    assert "4 runs in" in printed and "(0 failed), 0 skipped as done" in printed
    rows = read_rows(out)
    assert sorted((r["world"], r["seed"]) for r in rows) == [
        ("DM-USAR_red", 1),
        ("DM-USAR_red", 2),
        ("DM-USAR_yellow", 1),
        ("DM-USAR_yellow", 2),
    ]
    assert {r["run_id"] for r in rows} == {r.run_id for r in exp.runs}
    for r in rows:
        assert r["error"] is None and r["log"] == ""
        assert (r["experiment"], r["team"], r["robots_n"], r["clock"]) == ("two-by-two", "P2AT", 1, "lockstep")
        assert (r["duration_s"], r["wireless"], r["controller"]) == (12.0, "world", 'FrontierExplorer(bounds="auto")')
        assert 12.0 <= r["time_s"] <= 12.5  # the simulated time the score covers
        assert r["area_m2"] > 20.0 and r["distance_m"] > 1.0  # the explorer moved and its laser swept the floor
        assert math.isfinite(r["score"]) and r["score"] != 0.0
        assert r["victims_found"] >= 0 and r["collisions"] >= 0 and r["robots_lost"] == 0
        assert r["radio_contact_share"] == 0.0  # alone: nobody to be in contact with
        robots = json.loads(r["robots"])
        assert list(robots) == ["R1"] and robots["R1"]["class"] == "P2AT"
        assert robots["R1"]["area_m2"] == r["area_m2"]
        assert 0.0 < r["start_s"] < r["wall_s"] and r["control_s"] > 0.0 and r["stop_s"] > 0.0
        assert json.loads(r["config"])["seed"] == r["seed"]
    with open(out / "results.csv", newline="") as f:
        table = list(csv.DictReader(f))
    assert [t["run_id"] for t in table] == [r["run_id"] for r in rows]
    assert [float(t["score"]) for t in table] == [r["score"] for r in rows]

    # the same experiment again: every run is done, none runs
    again = run_sweep(exp, out, workers=2, progress=False)
    assert (again.rows, again.skipped, again.failed) == ([], 4, 0)
    assert score_columns(read_rows(out)) == score_columns(rows)

    # run afresh elsewhere: the same scores, to the last digit (lock-step, same seeds)
    fresh = run_sweep(exp, tmp_path / "fresh", workers=2, progress=False)
    assert len(fresh.rows) == 4 and fresh.failed == 0
    assert score_columns(fresh.rows) == score_columns(rows)

    # an edited experiment (one more seed) runs only its new runs; the old rows stay
    edited = load_experiment(write(tmp_path, TWO_BY_TWO.replace("seeds: [1, 2]", "seeds: [1, 2, 3]")))
    more = run_sweep(edited, out, workers=2, progress=False)
    assert more.skipped == 4 and sorted((r["world"], r["seed"]) for r in more.rows) == [
        ("DM-USAR_red", 3),
        ("DM-USAR_yellow", 3),
    ]
    stored = read_rows(out)
    assert len(stored) == 6
    assert {k: v for k, v in score_columns(stored).items() if k in score_columns(rows)} == score_columns(rows)


def test_a_failing_controller_is_recorded_with_its_error_and_run_again_next_time(local_ray, tmp_path, capsys):
    python = sys.executable
    path = write(
        tmp_path,
        f"""\
name: failing
duration: 5
runs:
  - controller: {{command: "{python} -c 'import sys; print(\\"no map of {{world}}\\"); sys.exit(3)'", label: broken}}
  - controller: {{brain: usarsim.brains.wander:Wander, params: {{pose_source: compass}}}}
  - controller: usarsim.brains.wander:Wander
""",
    )
    out = tmp_path / "results"
    assert main(["sweep", str(path), "--out", str(out), "--no-progress"]) == 1  # a run failed
    captured = capsys.readouterr()
    assert "3 runs in" in captured.out and "(2 failed)" in captured.out
    assert "failed: the controller exited with code 3: no map of DM-USAR_yellow" in captured.err
    rows = {r["controller"]: r for r in read_rows(out)}
    broken = rows["broken"]
    assert broken["error"] == "the controller exited with code 3: no map of DM-USAR_yellow"
    assert broken["score"] is None and broken["area_m2"] is None  # a failed run has no score
    assert broken["log"]  # the tail of the simulator's log
    bad = rows['Wander(pose_source="compass")']
    assert bad["error"].startswith("ValueError: pose_source must be odometry, ins or truth, got 'compass'")
    good = rows["Wander"]
    assert good["error"] is None and good["area_m2"] > 0.0 and 5.0 <= good["time_s"] <= 5.5
    # next time the failed runs run again (and fail again); the good one is done
    again = run_sweep(load_experiment(path), out, workers=2, progress=False)
    assert again.skipped == 1 and again.failed == 2 and len(read_rows(out)) == 3


# ---------------------------------------------------------------- the report


def constructed_rows() -> list[dict]:
    rows = []
    for world, base in (("DM-USAR_yellow", 100.0), ("DM-USAR_red", 60.0)):
        for controller, extra in (("Wander", 0.0), ("FrontierExplorer", 40.0)):
            for seed, noise in zip((1, 2, 3), (-4.0, 0.0, 4.0)):
                area = base + extra + noise
                rows.append(
                    {
                        "run_id": f"{world}-{controller}-{seed}",
                        "experiment": "made",
                        "world": world,
                        "seed": seed,
                        "team": "P2AT",
                        "robots_n": 1,
                        "wireless": "world",
                        "duration_s": 60.0,
                        "clock": "lockstep",
                        "controller": controller,
                        "score": area + 50.0 * (seed % 2),
                        "victims_found": seed % 2,
                        "victims_reported": 0,
                        "false_reports": 0,
                        "area_m2": area,
                        "distance_m": 10.0,
                        "collisions": 0,
                        "robots_lost": 0,
                        "radio_contact_share": 0.0,
                        "time_s": 60.2,
                        "wall_s": 3.0,
                        "error": None,
                        "log": "",
                    }
                )
    rows.append(dict(rows[0], run_id="failed-one", seed=4, score=None, area_m2=None, error="boom", log="tail"))
    return rows


def test_the_summary_gives_mean_deviation_and_an_interval_suited_to_each_score(tmp_path, capsys):
    assert t975(1) == 12.706 and t975(2) == 4.303 and t975(30) == 2.042
    assert 1.96 < t975(1000) < 1.99 and t975(40) == pytest.approx(2.021)
    s = Stat.of([96.0, 100.0, 104.0])
    assert s.mean == 100.0 and s.sd == pytest.approx(4.0)
    assert (s.ci_low, s.ci_high) == pytest.approx(
        (100.0 - 4.303 * 4.0 / math.sqrt(3), 100.0 + 4.303 * 4.0 / math.sqrt(3))
    )
    assert Stat.of([5.0]).sd is None and Stat.of([]).mean is None

    rows = constructed_rows()
    groups = summarize(rows)
    assert [(g.config["world"], g.config["controller"], len(g.seeds), g.failed) for g in groups] == [
        ("DM-USAR_yellow", "Wander", 3, 1),
        ("DM-USAR_yellow", "FrontierExplorer", 3, 0),
        ("DM-USAR_red", "Wander", 3, 0),
        ("DM-USAR_red", "FrontierExplorer", 3, 0),
    ]
    assert groups[1].stat("area_m2").mean == pytest.approx(140.0)  # the failed run is not averaged
    # victims found 1, 0, 1: a t interval would be [-0.77, 2.10]; the exact Poisson one of 2
    # victims in 3 runs is [0.2422, 7.2247] / 3
    victims = groups[1].stat("victims_found")
    assert victims.method == "poisson"
    assert (victims.ci_low, victims.ci_high) == pytest.approx((0.2422 / 3, 7.2247 / 3), abs=1e-4)
    assert groups[1].stat("robots_lost").ci_high == pytest.approx(1.0)  # 0 of 1 robot lost: at most the team

    write_rows(rows, tmp_path)
    assert main(["report", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert f"report written to {tmp_path / 'report.html'}" in out
    assert "±" not in out  # one notation: mean [low, high]
    assert out.count("mean [95 % CI]") == 3  # in the header of each score's column
    assert "FrontierExplorer" in out and "140.0 [130.1, 149.9]" in out  # area: 4.303 * 4 / sqrt(3) = 9.94
    assert "0.67 [0.08, 2.41]" in out and "-0.77" not in out
    assert "victims found: exact Poisson (Garwood)" in out and "area m²: Student's t, clipped at 0" in out
    report = build_report(tmp_path)
    assert report.axes == ("world", "controller")
    assert sorted(p.name for p in report.plots) == sorted(
        f"plot-{m}-by-{a}.png" for m in ("score", "victims_found", "area_m2") for a in ("world", "controller")
    )
    for p in report.plots:
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with open(tmp_path / "summary.csv", newline="") as f:
        summary = list(csv.DictReader(f))
    assert float(summary[1]["area_m2_mean"]) == pytest.approx(140.0)
    assert float(summary[1]["area_m2_ci95_high"]) == pytest.approx(140.0 + 4.303 * 4.0 / math.sqrt(3), abs=1e-4)
    assert float(summary[1]["victims_found_ci95_low"]) == pytest.approx(0.2422 / 3, abs=1e-4)
    page = report.html_path.read_text()
    assert page.count('<img src="data:image/png;base64,') == 6 and "boom" in page
    assert "±" not in page and page.count("mean [95 % CI, Poisson]") == 5  # the five counts (no message was sent)


def test_report_help_shows_plain_percent_signs(capsys):
    with pytest.raises(SystemExit) as info:
        main(["report", "--help"])
    assert info.value.code == 0
    text = capsys.readouterr().out
    assert "95 % confidence interval" in text and "%%" not in text


def test_report_without_results_says_so(tmp_path, capsys):
    assert main(["report", str(tmp_path)]) == 1
    assert "no results.parquet here" in capsys.readouterr().err


def test_a_two_by_two_sweep_of_a_simulated_minute_with_the_explorer(local_ray, tmp_path):
    """The issue's CI sweep: 2 worlds x 2 seeds of 60 simulated seconds, the shipped frontier
    explorer, lock-step; every run scored, the explorer sweeping more floor in a minute than in
    half of one."""
    exp = load_experiment(write(tmp_path, TWO_BY_TWO.replace("duration: 12", "duration: 60")))
    result = run_sweep(exp, tmp_path / "minute", workers=2, progress=False)
    assert len(result.rows) == 4 and result.failed == 0
    for r in result.rows:
        assert r["error"] is None and 60.0 <= r["time_s"] <= 60.5
        assert r["area_m2"] > 30.0 and r["distance_m"] > 2.0


def test_the_report_shows_the_team_messages_a_lossy_channel_lost(tmp_path, capsys):
    # the team of explorers talks over the ComServer; a channel that loses a third of the
    # messages counts them in the score, and the report's table shows them (none counted under
    # USARSim's ideal channel: a dash)
    from usarsim.sweep.worker import execute

    (tmp_path / "lossy.yaml").write_text("channel: {loss: {model: independent, rate: 0.33}}\n")
    command = (
        f"{sys.executable} -m usarsim.brains.team --port {{port}} --wcs-port {{wcs_port}} --robots 2 "
        "--seconds {seconds} --lockstep"
    )
    exp = load_experiment(
        write(
            tmp_path,
            f"name: lossy\nseeds: [1]\nteam: [{{robot: P2AT, count: 2}}]\nduration: 8\nclock: lockstep\n"
            f'controller: {{command: "{command}", label: team}}\ngrid:\n  wireless: [world, lossy.yaml]\n',
        )
    )
    rows = [execute(run) for run in exp.runs]
    assert [r["error"] for r in rows] == [None, None]
    by = {Path(r["wireless"]).name: r for r in rows}
    assert by["world"]["messages_lost"] is None  # not counted
    lossy = by["lossy.yaml"]
    sent = lossy["messages_delivered"] + lossy["messages_lost"]
    assert sent > 20 and lossy["messages_lost"] / sent == pytest.approx(0.33, abs=0.15)
    write_rows(rows, tmp_path / "results")
    assert main(["report", str(tmp_path / "results")]) == 0
    out = capsys.readouterr().out
    assert "messages lost" in out
    lines = {ln.split()[0]: ln for ln in out.splitlines() if ln.strip().startswith(("world", "lossy"))}
    assert lines["world"].rstrip().endswith("–")
    assert lines["lossy"].split()[-3] == f"{lossy['messages_lost']:.2f}"
