"""The ``usarsim`` command's argument handling, without starting anything: -v before and after
the command, --port-offset's port resolution, ``validate``'s names; and the simulation
runner's lag warning that ``usarsim serve`` prints."""

from __future__ import annotations

import dataclasses
import logging

import pytest

from usarsim.cli import DEFAULT_PORTS, build_parser, resolve_ports, validate_target
from usarsim.config.catalog import ROBOTS_DIR, WORLDS_DIR
from usarsim.errors import ConfigError
from usarsim.sim import runner as runner_module
from usarsim.sim.runner import SimulationRunner

# --------------------------------------------------------------------------- -v, -vv


def _verbose(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    return args.verbose + getattr(args, "verbose_after", 0)


@pytest.mark.parametrize(
    "argv, level",
    [
        (["serve"], 0),
        (["-v", "serve"], 1),
        (["serve", "-v"], 1),
        (["serve", "-vv"], 2),
        (["-vv", "serve"], 2),
        (["-v", "serve", "--verbose"], 2),
        (["validate", "P2AT", "-v"], 1),
        (["worlds", "-v"], 1),
        (["robots", "-vv"], 2),
        (["bench", "-v"], 1),
    ],
)
def test_verbose_before_and_after_the_command(argv, level):
    assert _verbose(argv) == level


def test_main_adds_up_both_places(monkeypatch):
    from usarsim import cli

    seen = []
    monkeypatch.setattr(cli, "_setup_logging", seen.append)
    monkeypatch.setattr(cli, "cmd_worlds", lambda args: 0)
    assert cli.main(["-v", "worlds", "-v"]) == 0
    assert seen == [2]


# --------------------------------------------------------------------------- --port-offset


def test_default_ports_are_the_servers_defaults():
    from usarsim.protocol.wireless import INTERFACE_PORT, WCS_PORT, WSS_PORT
    from usarsim.server.config import ServeConfig

    defaults = {f.name: f.default for f in dataclasses.fields(ServeConfig)}
    assert DEFAULT_PORTS == {
        "port": defaults["port"],
        "truth_port": defaults["truth_port"],
        "image_port": defaults["image_port"],
        "web_port": defaults["web_port"],
        "wcs_port": WCS_PORT,
        "wss_port": WSS_PORT,
        "cominterface_port": INTERFACE_PORT,
    }


def test_serve_options_default_to_none_so_that_the_offset_applies():
    args = build_parser().parse_args(["serve"])
    assert args.port_offset == 0
    assert all(getattr(args, name) is None for name in DEFAULT_PORTS)
    assert resolve_ports({name: getattr(args, name) for name in DEFAULT_PORTS}, args.port_offset) == DEFAULT_PORTS


def test_port_offset_adds_to_every_default():
    assert resolve_ports({}, 100) == {
        "port": 3100,
        "truth_port": 4089,
        "image_port": 5103,
        "web_port": 8180,
        "wcs_port": 5974,
        "wss_port": 50100,
        "cominterface_port": 7535,
    }


def test_an_explicit_port_keeps_its_value():
    ports = resolve_ports({"port": 4000, "web_port": 0, "truth_port": None}, 10)
    assert ports["port"] == 4000 and ports["web_port"] == 0
    assert ports["truth_port"] == 3999 and ports["wss_port"] == 50010


def test_a_wireless_config_port_keeps_its_value_and_the_command_line_wins():
    ports = resolve_ports({"cominterface_port": 9000}, 5, {"wcs_port": 6000, "cominterface_port": 6001})
    assert ports["wcs_port"] == 6000 and ports["cominterface_port"] == 9000
    assert resolve_ports({}, 5, {"wcs_port": None})["wcs_port"] == 5879


def test_an_offset_beyond_the_last_port_is_refused():
    with pytest.raises(ValueError, match=r"--wss-port \(50000\) at 65536"):
        resolve_ports({}, 15536)
    assert resolve_ports({"wss_port": 0}, 15536)["wss_port"] == 0  # nothing is pushed beyond
    assert resolve_ports({}, 15535)["wss_port"] == 65535


@pytest.mark.parametrize("text", ["-1", "15536", "x"])
def test_port_offset_option_rejects_nonsense(text, capsys):
    with pytest.raises(SystemExit) as exc:
        build_parser().parse_args(["serve", "--port-offset", text])
    assert exc.value.code == 2
    assert "expected a number 0..15535" in capsys.readouterr().err


# --------------------------------------------------------------------------- validate NAME


@pytest.mark.parametrize(
    "text, path",
    [
        ("DM-USAR_yellow", WORLDS_DIR / "DM-USAR_yellow.yaml"),
        ("dm-usar_yellow", WORLDS_DIR / "DM-USAR_yellow.yaml"),
        ("P2AT", ROBOTS_DIR / "P2AT.yaml"),
        ("usarbot.p2at", ROBOTS_DIR / "P2AT.yaml"),
    ],
)
def test_validate_finds_shipped_names(text, path):
    assert validate_target(text) == str(path)


def test_validate_keeps_paths(tmp_path):
    f = tmp_path / "P2AT"  # a file wins over a shipped name
    f.write_text("")
    assert validate_target(str(f)) == str(f)
    assert validate_target("missing.yaml") == "missing.yaml"  # its own error later: no such file
    assert validate_target("some/where") == "some/where"


def test_validate_unknown_name_names_the_known_ones():
    with pytest.raises(ConfigError, match=r"'Zerg2' is no file, shipped world or robot class .*DM-USAR_yellow"):
        validate_target("Zerg2")


# --------------------------------------------------------------------------- the lag warning


class _FakeSim:
    dt = 0.004

    def __init__(self):
        self.time = 0.0

    def advance(self, seconds):
        self.time += seconds

    def take_outputs(self, wait=True):
        return []


class _Clock:
    """perf_counter that returns ``times`` in turn, then the last one; after the second
    reading (the first look at the wall clock in the loop) it asks the runner to stop."""

    def __init__(self, runner, times):
        self.runner, self.times, self.calls = runner, list(times), 0

    def perf_counter(self):
        self.calls += 1
        if self.calls == 2:
            self.runner.queue.put(runner_module._Stop())  # the loop returns at its next look at the queue
        return self.times[min(self.calls, len(self.times)) - 1]


def _run_clocked(monkeypatch, behind_by):
    r = SimulationRunner(_FakeSim(), lambda outs: None, speed=1.0)
    monkeypatch.setattr(runner_module, "time", _Clock(r, [1000.0, 1000.0 + r.MAX_LAG_S + behind_by]))
    r._run_clocked()  # on this thread: returns at the stop
    return r


def test_no_lag_warning_when_nothing_shows_as_skipped(monkeypatch, caplog):
    with caplog.at_level(logging.WARNING, logger="usarsim.sim"):
        _run_clocked(monkeypatch, 1e-4)
    assert "behind real time" not in caplog.text


def test_lag_warning_names_what_was_skipped(monkeypatch, caplog):
    with caplog.at_level(logging.WARNING, logger="usarsim.sim"):
        _run_clocked(monkeypatch, 0.5)
    assert "simulation behind real time: 0.50 simulated s skipped (the clock" in caplog.text


def test_lag_warning_adds_up_and_comes_at_most_every_10_s(caplog):
    r = SimulationRunner(_FakeSim(), lambda outs: None)
    with caplog.at_level(logging.WARNING, logger="usarsim.sim"):
        r._note_lag(0.001, now=100.0)  # shows as 0.00: no warning yet
        r._note_lag(0.0, now=101.0)
        assert caplog.records == []
        r._note_lag(0.005, now=102.0)  # 0.006 in all: shown as 0.01
        assert [m.getMessage() for m in caplog.records] == [
            "simulation behind real time: 0.01 simulated s skipped (the clock does not catch up in bursts)"
        ]
        r._note_lag(0.3, now=105.0)  # within 10 s of the last warning: counted, not shown
        r._note_lag(0.2, now=113.0)
        assert caplog.records[-1].getMessage() == (
            "simulation behind real time: 0.50 simulated s skipped in the "
            "last 11 s (the clock does not catch up in bursts)"
        )
        r._note_lag(0.0, now=130.0)  # nothing since: nothing to say
        assert len(caplog.records) == 2


# --------------------------------------------------------------------------- --report-phases


@pytest.mark.parametrize(
    "argv, phases",
    [
        (["serve"], "grid"),
        (["serve", "--ros2", "P2AT@PlayerStart1:robot1"], "spread"),  # the bridge's readings in small groups
        (["serve", "--ros2", "P2AT", "--report-phases", "grid"], "grid"),
        (["serve", "--report-phases", "spread"], "spread"),
    ],
)
def test_serve_spreads_the_report_phases_with_the_ros2_bridge_unless_told(argv, phases):
    from usarsim.cli.serve import report_phases, run_options

    args = build_parser().parse_args(argv)
    assert report_phases(args) == phases
    assert run_options(args)["report_phases"] == phases  # what a recording keeps for its replay


def test_an_unknown_report_phase_is_refused_by_name(capsys):
    with pytest.raises(SystemExit):
        build_parser().parse_args(["serve", "--report-phases", "staggered"])
    assert "spread" in capsys.readouterr().err
