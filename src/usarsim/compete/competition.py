"""The competition file: teams, the scenario set they all play, and how runs earn points.

A competition file is YAML (docs/competitions.md lists every key)::

    name: rescue-cup
    scenarios:
      worlds: [DM-USAR_yellow, DM-USAR_orange]
      variants: 2                  # per world: variant numbers drawn from the secret
      secret: env:CUP_SECRET       # hidden: only who holds the secret knows the arenas
      seeds: [0]
    team: [{robot: P2AT, count: 2}]
    duration: 60
    teams:
      - {name: frontier, controller: {brain: usarsim.brains.frontier:FrontierExplorer, params: {bounds: auto}}}
      - {name: mybot, controller: {command: "./mybot --host {host} --port {port} --map {map}"}}

Every team plays every scenario (a world, a variant of it, a simulator seed) with the same
robots, radio, clock and time, each run in a simulator of its own (usarsim.sweep's runs, on
Ray).  Errors name the file, the key and what is allowed.
"""

from __future__ import annotations

import hashlib
import os
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from usarsim.config.reader import Section, load_yaml
from usarsim.sweep.experiment import Reader
from usarsim.sweep.runs import DEFAULT_TIMEOUT_S, DEFAULTS, Experiment, Run, team_label

# variant numbers drawn from a secret lie in [0, VARIANT_RANGE)
VARIANT_RANGE = 1_000_000


@dataclass(frozen=True)
class Points:
    """How a run earns points: ``score`` times the run's combined score (docs/scoring.md),
    ``map`` times the map's quality (coverage x accuracy, from 0 to 1) and ``map_victims`` per
    victim placed on the map within 1 m."""

    score: float = 1.0
    map: float = 100.0
    map_victims: float = 20.0

    def of(self, row: dict[str, Any]) -> float | None:
        """The points of a run's row (None for a failed run)."""
        if row.get("error") or row.get("score") is None:
            return None
        quality = (row.get("map_coverage") or 0.0) * (row.get("map_accuracy") or 0.0)
        return self.score * float(row["score"]) + self.map * quality + self.map_victims * (row.get("map_victims") or 0)


@dataclass(frozen=True)
class Scenario:
    """One scenario of the set: ``label`` (S1, S2, ...), a world, its variant, a simulator seed."""

    label: str
    world: str
    variant: int | None
    seed: int


@dataclass(frozen=True)
class Competition:
    """A competition file read: its teams, its scenario set and points, and every run (each team
    over each scenario)."""

    name: str
    path: str
    description: str
    teams: tuple[str, ...]
    scenarios: tuple[Scenario, ...]
    points: Points
    hidden: bool  # the variants were drawn from a secret given outside the file
    runs: tuple[Run, ...]  # team by team, scenario by scenario

    def experiment(self) -> Experiment:
        return Experiment(name=self.name, path=self.path, description=self.description, runs=self.runs, axes=())

    def scenario_of(self, run: Run) -> Scenario:
        for s in self.scenarios:
            if (s.world, s.variant, s.seed) == (run.world, run.variant, run.seed):
                return s
        raise KeyError(run.run_id)


def load_competition(path: str | Path, out_dir: str | Path | None = None) -> Competition:
    """Read and check a competition file (``out_dir``: where its results go, by default
    ``results/<name>``; the runs keep their maps in its ``maps`` folder)."""
    p = Path(path)
    return _Reader(p).read(load_yaml(p), out_dir)


class _Reader(Reader):
    def read(self, data: dict, out_dir: str | Path | None = None) -> Competition:  # type: ignore[override]
        top = Section(data, path=self.file)
        name = top.str("name", self.path.stem)
        if not re.match(r"^[\w.\-]+$", name):
            raise top.error("name", f"use letters, digits, '.', '-' and '_' only, got {name!r}")
        description = top.str("description", "") if top.has("description") else ""
        self.robot_dirs = tuple(self._robot_dirs(top.list("robot_dirs", [])))
        timeout = top.float("timeout", DEFAULT_TIMEOUT_S, min=0.0, min_exclusive=True)
        team_specs = self.team(top.raw("team", DEFAULTS["team"]), "team")
        wireless = self.wireless(top.raw("wireless", DEFAULTS["wireless"]), "wireless")
        duration = self.duration(top.raw("duration", DEFAULTS["duration"]), "duration")
        clock = self.clock(top.raw("clock", DEFAULTS["clock"]), "clock")
        points = self._points(top.section("points", {}))
        scenarios, hidden = self._scenarios(top.section("scenarios"), name)
        out = Path(out_dir) if out_dir is not None else Path("results") / name
        maps_dir = str((out / "maps").resolve())
        names: list[str] = []
        runs: list[Run] = []
        for i, t in enumerate(top.entries("teams", required=True)):
            tname = t.str("name")
            if not re.match(r"^[\w.\-]+$", tname):
                raise t.error("name", f"use letters, digits, '.', '-' and '_' only, got {tname!r}")
            if tname in names:
                raise t.error("name", f"two teams are named {tname!r}")
            names.append(tname)
            controller = self.controller(t.raw("controller"), f"teams[{i}].controller")
            if controller.isolate and clock == "lockstep":
                raise t.error("controller", "isolated controllers need 'clock: max' (docs/experiments.md)")
            controller = replace(controller, label=tname)
            for s in scenarios:
                world = self.world(s.world, f"scenarios.worlds ({s.world})")
                members = self.place_team(team_specs, world, "team")
                runs.append(
                    Run(
                        experiment=name,
                        world=world[0],
                        seed=s.seed,
                        team=members,
                        team_label=team_label(team_specs),
                        wireless=wireless,
                        duration_s=duration,
                        clock=clock,
                        controller=controller,
                        timeout_s=timeout,
                        robot_dirs=self.robot_dirs,
                        cwd=str(self.folder),
                        variant=s.variant,
                        maps_dir=maps_dir,
                    )
                )
        if not names:
            raise top.error("teams", "a competition needs at least one team")
        top.finish()
        return Competition(name, self.file, description, tuple(names), scenarios, points, hidden, tuple(runs))

    def _points(self, s: Section) -> Points:
        d = Points()
        out = Points(
            score=s.float("score", d.score, min=0.0),
            map=s.float("map", d.map, min=0.0),
            map_victims=s.float("map_victims", d.map_victims, min=0.0),
        )
        s.finish()
        return out

    def _scenarios(self, s: Section, name: str) -> tuple[tuple[Scenario, ...], bool]:
        worlds = s.list("worlds", ["DM-USAR_yellow"])
        if not worlds or not all(isinstance(w, str) and w.strip() for w in worlds):
            raise s.error("worlds", f"a list of worlds (usarsim worlds) or world files, got {worlds!r}")
        seeds = self.seeds(s.raw("seeds", [0]), f"{s.key}.seeds")
        raw = s.raw("variants", 1)
        secret_text = s.str("secret", "") if s.has("secret") else ""
        hidden = secret_text.startswith("env:")
        if hidden:
            var = secret_text[4:]
            secret = os.environ.get(var, "")
            if not secret:
                raise s.error("secret", f"the environment variable {var} that holds the secret is not set")
        else:
            secret = secret_text or name
        out: list[Scenario] = []
        for world in worlds:
            if isinstance(raw, list):
                if not raw or not all(isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in raw):
                    raise s.error("variants", f"a number of variants, or a list of variant numbers >= 0, got {raw!r}")
                if secret_text:
                    raise s.error("secret", "a secret draws the variants: give 'variants' as a number with it")
                variants: list[int | None] = list(raw)
            elif isinstance(raw, int) and not isinstance(raw, bool) and raw >= 0:
                # 0: the worlds as written
                variants = [draw_variant(secret, world, k) for k in range(raw)] if raw else [None]
            else:
                raise s.error("variants", f"a number of variants, or a list of variant numbers >= 0, got {raw!r}")
            for v in variants:
                for seed in seeds:
                    out.append(Scenario(f"S{len(out) + 1}", world, v, seed))
        s.finish()
        return tuple(out), hidden


def draw_variant(secret: str, world: str, k: int) -> int:
    """The ``k``-th variant number of ``world`` drawn from ``secret``."""
    digest = hashlib.sha256(f"usarsim-competition:{secret}:{world}:{k}".encode()).digest()
    return int.from_bytes(digest[:8], "big") % VARIANT_RANGE
