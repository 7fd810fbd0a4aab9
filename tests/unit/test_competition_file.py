"""The competition file (usarsim.compete.competition): every team over the same scenarios, the
variants drawn from the secret, and errors that name the key; the leaderboard's tally."""

from __future__ import annotations

import pytest

from usarsim.compete.competition import Points, draw_variant, load_competition
from usarsim.compete.leaderboard import leaderboard_rows, tally
from usarsim.errors import ConfigError

BASE = """\
name: cup
scenarios:
  worlds: [DM-USAR_yellow, DM-USAR_red]
  variants: 2
  seeds: [1, 2]
team: [{robot: P2AT, count: 2}]
duration: 30
teams:
  - {name: a, controller: usarsim.brains.wander:Wander}
  - {name: b, controller: {brain: usarsim.brains.frontier:FrontierExplorer, params: {bounds: auto}}}
"""


def _load(tmp_path, text: str):
    p = tmp_path / "cup.yaml"
    p.write_text(text)
    return load_competition(p, tmp_path / "out")


def test_every_team_plays_the_same_scenarios(tmp_path):
    comp = _load(tmp_path, BASE)
    assert comp.teams == ("a", "b")
    assert [s.label for s in comp.scenarios] == [f"S{i}" for i in range(1, 9)]  # 2 worlds x 2 variants x 2 seeds
    assert len(comp.runs) == 16 and len({r.run_id for r in comp.runs}) == 16
    by_team = {t: [(r.world, r.variant, r.seed) for r in comp.runs if r.controller.label == t] for t in comp.teams}
    assert by_team["a"] == by_team["b"]
    assert all(len(r.team) == 2 and r.duration_s == 30 and r.maps_dir.endswith("maps") for r in comp.runs)
    # the variants come from the secret (by default the competition's name): the same file, the same set
    assert comp.scenarios[0].variant == draw_variant("cup", "DM-USAR_yellow", 0)
    assert [s.variant for s in _load(tmp_path, BASE).scenarios] == [s.variant for s in comp.scenarios]
    other = _load(tmp_path, BASE.replace("seeds: [1, 2]", "seeds: [1, 2]\n  secret: other"))
    assert [s.variant for s in other.scenarios] != [s.variant for s in comp.scenarios]
    assert not comp.hidden


def test_a_hidden_secret_comes_from_the_environment(tmp_path, monkeypatch):
    text = BASE.replace("seeds: [1, 2]", "seeds: [1]\n  secret: env:CUP_SECRET")
    with pytest.raises(ConfigError, match="CUP_SECRET"):
        _load(tmp_path, text)
    monkeypatch.setenv("CUP_SECRET", "s3cret")
    comp = _load(tmp_path, text)
    assert comp.hidden and comp.scenarios[0].variant == draw_variant("s3cret", "DM-USAR_yellow", 0)


@pytest.mark.parametrize(
    "change, key",
    [
        (("name: a,", "name: b,"), "two teams"),
        (("variants: 2", "variants: -1"), "variants"),
        (("worlds: [DM-USAR_yellow, DM-USAR_red]", "worlds: [DM-USAR_yelow]"), "DM-USAR_yellow"),
        (("duration: 30", "duration: 30\npoints: {scroe: 1}"), "scroe"),
        (("usarsim.brains.wander:Wander", "usarsim.brains.wander:Wandr"), "Wandr"),
        (("duration: 30", "duration: 30\ncolour: red"), "colour"),
    ],
)
def test_a_wrong_competition_file_is_refused_naming_the_key(tmp_path, change, key):
    with pytest.raises(ConfigError, match=key):
        _load(tmp_path, BASE.replace(*change))


def test_the_tally_ranks_teams_by_their_points_over_the_scenarios(tmp_path):
    comp = _load(tmp_path, BASE.replace("seeds: [1, 2]", "seeds: [1]"))
    rows = []
    for r in comp.runs:
        good = r.controller.label == "b"
        rows.append(
            {
                "run_id": r.run_id,
                "score": 100.0 if good else 40.0,
                "map_coverage": 0.5 if good else None,
                "map_accuracy": 0.8 if good else None,
                "map_victims": 1 if good else None,
                "error": None,
            }
        )
    rows[0]["error"], rows[0]["score"] = "the controller exited with code 1", None  # a failed run of a: 0 points
    board = leaderboard_rows(tally(comp, rows))
    assert [b["team"] for b in board] == ["b", "a"]
    b = board[0]
    per_run = Points().of(rows[-1])
    assert per_run == pytest.approx(100.0 + 100.0 * 0.4 + 20.0)
    assert b["total"] == pytest.approx(4 * per_run) and b["mean"] == pytest.approx(per_run)
    assert b["ci_low"] == pytest.approx(per_run) and b["failed"] == 0  # the same points everywhere: no spread
    a = board[1]
    assert a["total"] == pytest.approx(3 * 40.0) and a["failed"] == 1 and a["ci_low"] < a["mean"] < a["ci_high"]
