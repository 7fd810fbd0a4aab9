"""The radio propagation models (manual 3.2.4; protocol.md 12.2), their configuration
(world section, USARComServer.ini-style file, command line) and the ComServer link framing."""

from __future__ import annotations

import math

import pytest

from usarsim.config.world import WirelessConfig
from usarsim.config.world_file import load_world
from usarsim.errors import ConfigError
from usarsim.protocol.wireless import SendParser
from usarsim.sim.radio import PRESETS, RadioModel, pair_key, resolve_model, waf_signal_dbm
from usarsim.sim.wireless_file import load_wireless_file

MANUAL = dict(pd0_dbm=-49.67, d0_m=2.0, path_loss_exponent=1.09, wall_db=6.625, max_walls=5)


# --------------------------------------------------------------------------- the formula


@pytest.mark.parametrize(
    "distance, walls, expected",
    [
        # S = -49.67 - 10.9 log10(d / 2) - min(walls, 5) 6.625, worked out by hand
        (2.0, 0, -49.67),  # at the reference distance
        (20.0, 0, -60.57),  # log10(10) = 1
        (4.0, 1, -59.5762),  # 10.9 x 0.30103 = 3.28123; - 6.625
        (200.0, 2, -84.72),  # 10.9 x 2 = 21.8; - 13.25
        (20.0, 5, -93.695),  # 5 walls: 33.125 dB
        (20.0, 6, -93.695),  # the cap: a sixth wall costs nothing more
        (20.0, 40, -93.695),
        (1.0, 0, -46.38877),  # closer than d0: stronger than P(d0)
    ],
)
def test_the_wall_attenuation_factor_formula_to_a_hundredth_of_a_db(distance, walls, expected):
    assert waf_signal_dbm(distance, walls, **MANUAL) == pytest.approx(expected, abs=0.01)
    assert PRESETS["waf"].signal_dbm(distance, walls) == pytest.approx(expected, abs=0.01)


def test_the_presets_hold_the_manual_and_the_later_code_constants():
    waf, w09, dist, perfect = (PRESETS[k] for k in ("waf", "waf2009", "distance", "perfect"))
    assert (waf.pd0_dbm, waf.d0_m, waf.path_loss_exponent, waf.max_walls, waf.wall_db, waf.cutoff_dbm) == (
        -49.67,
        2.0,
        1.09,
        5,
        6.625,
        -93.0,
    )
    assert (w09.pd0_dbm, w09.d0_m, w09.path_loss_exponent, w09.max_walls, w09.wall_db, w09.cutoff_dbm) == (
        -49.67,
        2.0,
        1.0,
        None,
        6.325,
        -93.0,
    )
    # waf2009: -49.67 - 10 log10(10 / 2) - 6 x 6.325 (no cap) = -94.61897
    assert w09.signal_dbm(10.0, 6) == pytest.approx(-94.619, abs=0.01)
    # distance only: walls do not matter
    assert dist.signal_dbm(20.0, 9) == pytest.approx(-60.57, abs=0.01) == dist.signal_dbm(20.0, 0)
    assert perfect.signal_dbm(1e6, 100) == 0.0 and perfect.holds(-500.0)
    assert waf.holds(-93.0) and not waf.holds(-93.001)
    assert waf.cache_distance_m == 1.0


def test_a_range_can_be_worked_out_from_the_formula():
    # five walls or more: the manual's model reaches the cutoff at d = 2 x 10^((43.33 - 33.125) / 10.9)
    d = 2.0 * 10 ** ((-49.67 + 93.0 - 5 * 6.625) / 10.9)
    assert d == pytest.approx(17.27, abs=0.01)
    assert PRESETS["waf"].holds(PRESETS["waf"].signal_dbm(d - 0.01, 6))
    assert not PRESETS["waf"].holds(PRESETS["waf"].signal_dbm(d + 0.01, 6))


def test_zero_distance_does_not_break_the_formula():
    assert math.isfinite(PRESETS["waf"].signal_dbm(0.0, 0))


def test_pairs_ignore_order_and_case():
    assert pair_key("Bob", "alice") == pair_key("ALICE", "bob") == ("alice", "bob")


# --------------------------------------------------------------------------- configuration


def test_layers_world_then_file_then_the_command_line():
    world = WirelessConfig(model="waf2009", cutoff_dbm=-80.0)
    file = WirelessConfig(wall_db=10.0, max_walls=-1)
    m = resolve_model(world, file)
    assert (m.name, m.path_loss_exponent, m.cutoff_dbm, m.wall_db, m.max_walls) == ("waf2009", 1.0, -80.0, 10.0, None)
    # the command line picks the model; the constants the layers give still apply
    m = resolve_model(world, file, model="waf")
    assert (m.name, m.path_loss_exponent, m.cutoff_dbm, m.wall_db) == ("waf", 1.09, -80.0, 10.0)
    assert resolve_model() == RadioModel() == PRESETS["waf"]
    assert resolve_model(None, WirelessConfig(model="perfect")).name == "perfect"


def test_a_usarcomserver_ini_file_is_read(tmp_path):
    p = tmp_path / "USARComServer.ini"
    p.write_text("""\
; as USARSim's USARComServer.ini (manual 3.2.4.2)
[USARBotAPI.ComServer]
ListenPort=6000
bDebug=False

[USARBotAPI.ComConnection]
bDebug=True
ePdo=-50.0
eDo=1
eN=2.0
eCutoff=-85
eMaxObs=3
eAttenFac=7.5
# extensions
model=waf
CacheDistance=0.5
""")
    f = load_wireless_file(p)
    assert f.listen_port == 6000 and f.interface_port is None and f.debug
    m = resolve_model(f.radio)
    assert (m.pd0_dbm, m.d0_m, m.path_loss_exponent, m.cutoff_dbm, m.max_walls, m.wall_db, m.cache_distance_m) == (
        -50.0,
        1.0,
        2.0,
        -85.0,
        3,
        7.5,
        0.5,
    )


@pytest.mark.parametrize(
    "text, message",
    [
        ("eAtenFac=5\n", "unknown key 'eAtenFac' (did you mean 'eAttenFac'?)"),
        ("eN=fast\n", "expected a number, got 'fast'"),
        ("ListenPort=99999\n", "expected a port number"),
        ("Model=magic\n", "is not a radio model"),
        ("eDo=0\n", "eDo > 0"),
        ("just words\n", "expected 'Key=Value'"),
    ],
)
def test_a_bad_ini_file_names_the_line_and_the_key(tmp_path, text, message):
    p = tmp_path / "bad.ini"
    p.write_text("[USARBotAPI.ComConnection]\n" + text)
    with pytest.raises(ConfigError) as exc:
        load_wireless_file(p)
    assert message in str(exc.value) and str(p) in str(exc.value)
    if "line" in str(exc.value):
        assert "line 2" in str(exc.value)


WORLD = """\
name: Radio
floor: {center: [0.0, 0.0], size: [10.0, 10.0]}
start_poses:
  - {name: S, location: [0.0, 0.0, -0.2]}
"""


def test_a_world_chooses_its_radio_model(tmp_path):
    p = tmp_path / "w.yaml"
    p.write_text(WORLD + "wireless: {model: waf2009, eCutoff: -80, eMaxObs: null, cache_distance_m: 2.0}\n")
    w = load_world(p)
    assert w.wireless == WirelessConfig(model="waf2009", cutoff_dbm=-80.0, max_walls=-1, cache_distance_m=2.0)
    m = resolve_model(w.wireless)
    assert (m.name, m.cutoff_dbm, m.max_walls, m.cache_distance_m) == ("waf2009", -80.0, None, 2.0)
    p.write_text(WORLD + "wireless: {eCutof: -80}\n")
    with pytest.raises(ConfigError, match=r"wireless.eCutof: unknown key 'eCutof' \(did you mean 'eCutoff'\?\)"):
        load_world(p)
    p.write_text(WORLD + "wireless: {model: Wall Model}\n")
    with pytest.raises(ConfigError, match="wireless.model"):  # not a model's name at all
        load_world(p)
    # a name no model has (a plugin's may be registered later) is refused when it is resolved
    p.write_text(WORLD + "wireless: {model: wall}\n")
    with pytest.raises(ConfigError, match=r"unknown radio model 'wall'; allowed: distance, "):
        resolve_model(load_world(p).wireless)


# --------------------------------------------------------------------------- ComServer link framing


def feed_all(parser: SendParser, data: bytes, chunk: int) -> list:
    out = []
    for i in range(0, len(data), chunk):
        out += parser.feed(data[i : i + chunk])
    return out


@pytest.mark.parametrize("chunk", [1, 2, 3, 7, 1000])
def test_send_frames_are_binary_safe_in_any_split(chunk):
    payload = bytes(range(256)) + b";SEND 3 x;"
    data = b"SEND 266 " + payload + b";\r\nSEND 0 ;  SEND 4 ab;c;CLOSE ;"
    assert feed_all(SendParser(), data, chunk) == [payload, b"", b"ab;c", SendParser.CLOSE]


def test_send_frames_that_lie_are_dropped_and_the_stream_recovers():
    p = SendParser(max_bytes=100)
    out = p.feed(b"SEND 3 abcd;SEND 2 ok;")  # too short: 'd' where ';' should be
    assert out[0].startswith("SEND of 3 bytes not followed by ';'") and out[1:] == [b"ok"]
    out = p.feed(b"SEND 9 abc;SEND 2 no;SEND 2 ok;")  # too long: swallows the next frame
    assert len(out) == 2 and isinstance(out[0], str) and out[1] == b"ok"
    out = p.feed(b"send 2 no;HELLO;SEND x;SEND 101 x;SEND 12345678901 x;SEND 2 ok;")
    assert [o for o in out if isinstance(o, bytes)] == [b"ok"] and len(out) == 6
    assert not p.partial
    p.feed(b"SEND 10 abc")
    assert p.partial
