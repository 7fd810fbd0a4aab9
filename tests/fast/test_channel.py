"""The radio channel beyond the path loss (usarsim.sim.channel): capacity and queueing, delay,
the loss models, shadowing and fading, reading the ``channel`` section, and determinism."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usarsim.config.channel import ChannelConfig, read_channel
from usarsim.config.reader import Section
from usarsim.errors import ConfigError
from usarsim.sim.channel import (
    EB_N0_AT_CUTOFF_DB,
    Channel,
    LinkView,
    Shadowing,
    check_channel,
    packet_error_rate,
)

NEAR = LinkView(signal_dbm=-60.0, cutoff_dbm=-93.0, distance_m=10.0, holds=True)


def always(view: LinkView | None = NEAR):
    return lambda src, dst: view


def run(ch: Channel, until: float, step: float = 0.01, view=None):
    """Every delivery and drop up to ``until``, asking at each ``step`` as the server does."""
    got, lost = [], []
    t = 0.0
    while t <= until + 1e-9:
        d, x = ch.due(t, view or always())
        got += d
        lost += x
        t = round(t + step, 9)
    return got, lost


def test_a_megabyte_over_a_link_capped_at_125_kb_s_takes_8_seconds():
    ch = Channel(ChannelConfig(link_bytes_per_s=125_000.0, queue_bytes=2_000_000), seed=1)
    for k in range(1000):  # 1,000,000 bytes in messages of 1,000
        assert ch.submit(0.0, "A", "B", bytes(1000), token=k) is None
    got, lost = run(ch, 10.0)
    assert not lost and [d.token for d in got] == list(range(1000))
    # the last byte leaves at 8 s (and the message is asked for at the next 10 ms)
    assert got[-1].at == pytest.approx(8.0, abs=1e-6)
    assert got[0].at == pytest.approx(0.008, abs=1e-6)  # one message's serialisation
    counts = ch.counts()[("a", "b")]
    assert counts.delivered == 1000 and counts.delivered_bytes == 1_000_000


def test_a_radio_shares_its_capacity_between_its_links_and_a_full_queue_drops():
    ch = Channel(ChannelConfig(radio_bytes_per_s=1000.0, queue_bytes=3000), seed=1)
    assert ch.submit(0.0, "A", "B", bytes(1000), 1) is None
    assert ch.submit(0.0, "A", "C", bytes(1000), 2) is None
    assert ch.submit(0.0, "A", "B", bytes(1000), 3) is None
    drop = ch.submit(0.0, "A", "C", bytes(1000), 4)  # 4,000 bytes would wait: no room
    assert drop is not None and drop.cause == "capacity" and drop.token == 4
    assert ch.submit(0.0, "D", "B", bytes(1000), 5) is None  # another radio has its own queue
    got, _ = run(ch, 4.0)
    # each radio sends at its own 1,000 bytes a second
    assert [(d.token, round(d.at, 6)) for d in got] == [(1, 1.0), (5, 1.0), (2, 2.0), (3, 3.0)]
    assert ch.counts()[("a", "c")].dropped["capacity"] == 1


def test_delay_is_serialisation_plus_distance_latency_and_jitter_in_order():
    cfg = ChannelConfig(link_bytes_per_s=1e6, latency_s=0.05, jitter_s=0.02)
    ch = Channel(cfg, seed=3)
    for k in range(200):
        ch.submit(k * 0.001, "A", "B", bytes(100), k)
    got, _ = run(ch, 1.0, step=0.001)
    assert [d.token for d in got] == list(range(200))  # in the order sent
    delays = np.array([d.at - d.sent_at for d in got])
    base = 100 / 1e6 + 10.0 / 299_792_458.0 + 0.05
    assert delays.min() >= base - 1e-12
    assert delays.max() <= base + 0.02 + 1e-12
    assert delays.std() > 0.002  # the jitter is there


def test_independent_loss_of_20_percent_drops_20_percent_of_10000_messages():
    ch = Channel(ChannelConfig(loss="independent", loss_settings={"rate": 0.2}), seed=7)
    for k in range(10_000):
        ch.submit(0.0, "A", "B", b"x", k)
    got, lost = ch.due(1.0, always())
    assert len(got) + len(lost) == 10_000
    assert abs(len(lost) / 10_000 - 0.2) < 0.02
    assert {d.cause for d in lost} == {"loss"}


def bursts(flags: list[bool]) -> list[int]:
    """The lengths of the runs of True."""
    out, n = [], 0
    for f in flags:
        if f:
            n += 1
        elif n:
            out.append(n)
            n = 0
    return out + ([n] if n else [])


def test_gilbert_elliott_loses_in_bursts_of_the_documented_length():
    settings = {"p_good_bad": 0.02, "p_bad_good": 0.25, "loss_good": 0.0, "loss_bad": 1.0}
    ch = Channel(ChannelConfig(loss="gilbert_elliott", loss_settings=settings), seed=11)
    n = 50_000
    for k in range(n):
        ch.submit(0.0, "A", "B", b"x", k)
    _, lost = ch.due(1.0, always())
    dropped = {d.token for d in lost}
    runs = bursts([k in dropped for k in range(n)])
    # a bad spell lasts 1 / p_bad_good = 4 messages on average; the long-run loss is
    # p_good_bad / (p_good_bad + p_bad_good) = 0.074
    assert np.mean(runs) == pytest.approx(4.0, rel=0.08)
    assert len(dropped) / n == pytest.approx(0.02 / 0.27, rel=0.08)
    # and far burstier than independent loss at the same rate (mean run 1 / (1 - p) = 1.08)
    assert np.mean(runs) > 3.0


def test_out_of_range_messages_are_dropped_as_such():
    ch = Channel(ChannelConfig(link_bytes_per_s=1000.0), seed=1)
    ch.submit(0.0, "A", "B", bytes(500), 1)
    down = LinkView(signal_dbm=-95.0, cutoff_dbm=-93.0, distance_m=100.0, holds=False)
    got, lost = run(ch, 1.0, view=always(down))
    assert not got and [(d.token, d.cause) for d in lost] == [(1, "range")]
    assert ch.submit(0.0, "A", "Z", b"x", 2) is None
    _, lost = ch.due(1.0, always(None))  # no such robot
    assert [d.cause for d in lost] == ["range"]


def test_the_packet_error_rate_falls_with_the_margin_and_rises_with_the_length():
    # at the cutoff: the receiver sensitivity's 8 % of 1,024-byte messages (IEEE 802.11b)
    assert packet_error_rate(0.0, 1024) == pytest.approx(0.08, abs=1e-9)
    assert EB_N0_AT_CUTOFF_DB == pytest.approx(10.34, abs=0.01)
    assert packet_error_rate(-3.0, 1024) > 0.9
    assert packet_error_rate(2.0, 1024) < 1e-3
    assert packet_error_rate(0.0, 100) < packet_error_rate(0.0, 1024) < packet_error_rate(0.0, 4000)
    # the signal model with Rayleigh fading: most messages well above the cutoff get through,
    # those near it far fewer
    counts = {}
    for margin in (3.0, 30.0):
        ch = Channel(ChannelConfig(loss="signal", fading="rayleigh"), seed=5)
        for k in range(4000):
            ch.submit(0.0, "A", "B", bytes(1024), k)
        view = LinkView(signal_dbm=-93.0 + margin, cutoff_dbm=-93.0, distance_m=5.0, holds=True)
        got, _ = ch.due(1.0, always(view))
        counts[margin] = len(got) / 4000
    assert counts[30.0] > 0.99 and counts[3.0] < 0.7


def test_shadowing_is_a_draw_per_pair_kept_until_an_end_moves():
    sh = Shadowing(ChannelConfig(shadowing_db=4.0, shadowing_wall_db=2.0, shadowing_distance_m=2.0), seed=9)
    pair = ("a", "b")
    first = sh.offset_db(pair, (0, 0, 0), (10, 0, 0), walls=0)
    assert sh.offset_db(pair, (1.5, 0, 0), (10, 0, 0), walls=0) == first  # moved less than 2 m
    second = sh.offset_db(pair, (2.5, 0, 0), (10, 0, 0), walls=0)
    assert second != first
    # the spread: 4 dB in the open, 4 + 2 x 3 dB behind three walls
    draws = [
        Shadowing(ChannelConfig(shadowing_db=4.0), seed=s).offset_db(pair, (0, 0, 0), (1, 0, 0), 0) for s in range(2000)
    ]
    assert np.std(draws) == pytest.approx(4.0, rel=0.08)
    walled = [
        Shadowing(ChannelConfig(shadowing_db=4.0, shadowing_wall_db=2.0), seed=s).offset_db(
            pair, (0, 0, 0), (1, 0, 0), 3
        )
        for s in range(2000)
    ]
    assert np.std(walled) == pytest.approx(10.0, rel=0.08)
    assert Shadowing(ChannelConfig(), seed=1).offset_db(pair, (0, 0, 0), (1, 0, 0), 5) == 0.0


def test_the_same_seed_and_messages_give_the_same_deliveries():
    cfg = ChannelConfig(
        loss="gilbert_elliott", fading="rayleigh", link_bytes_per_s=50_000.0, latency_s=0.01, jitter_s=0.01
    )

    def once(seed: int):
        ch = Channel(cfg, seed=seed)
        for k in range(300):
            ch.submit(k * 0.003, "A" if k % 3 else "C", "B", bytes(50 + k % 7), k)
        got, lost = run(ch, 2.0, step=0.004)
        return [(d.token, d.at) for d in got], [(d.token, d.cause) for d in lost]

    assert once(4) == once(4)
    assert once(4) != once(5)
    # a link's fate does not depend on what another link carries
    a_only = Channel(cfg, seed=4)
    for k in range(300):
        if k % 3:
            a_only.submit(k * 0.003, "A", "B", bytes(50 + k % 7), k)
    got, _ = run(a_only, 2.0, step=0.004)
    assert [x for x in once(4)[0] if x[0] % 3] == [(d.token, d.at) for d in got]


def test_the_channel_section_is_read_and_checked():
    cfg = read_channel(
        Section(
            {
                "shadowing_db": 4,
                "fading": "rayleigh",
                "loss": {"model": "gilbert_elliott", "p_good_bad": 0.05},
                "link_bytes_per_s": 125000,
                "latency_s": 0.02,
            },
            path="w.yaml",
            key="wireless.channel",
        )
    )
    assert cfg.loss == "gilbert_elliott" and cfg.loss_settings == {"p_good_bad": 0.05}
    assert cfg.link_bytes_per_s == 125000.0 and not cfg.ideal
    check_channel(cfg)
    assert ChannelConfig().ideal
    with pytest.raises(ConfigError, match="no setting 'p_bad'"):
        check_channel(ChannelConfig(loss="gilbert_elliott", loss_settings={"p_bad": 0.1}))
    with pytest.raises(ConfigError, match="unknown loss model 'burst'"):
        check_channel(ChannelConfig(loss="burst"))
    with pytest.raises(ConfigError, match="fading"):
        read_channel(Section({"fading": "rician"}, path="w.yaml", key="wireless.channel"))
    with pytest.raises(ConfigError, match="unknown key 'latency'"):
        read_channel(Section({"latency": 0.1}, path="w.yaml", key="wireless.channel"))
    assert math.isinf(Channel(ChannelConfig(), seed=0).rate)


def test_a_yaml_wireless_configuration_file_carries_the_channel_and_wins_over_the_world(tmp_path):
    from usarsim.config.world import WirelessConfig
    from usarsim.sim.radio import resolve_channel, resolve_model
    from usarsim.sim.wireless_file import load_wireless_file

    p = tmp_path / "radio.yaml"
    p.write_text("wireless:\n  model: waf2009\n  eCutoff: -80\n  channel: {loss: {model: independent, rate: 0.1}}\n")
    layer = load_wireless_file(p).radio
    world = WirelessConfig(channel=ChannelConfig(latency_s=0.5))
    assert resolve_model(world, layer).name == "waf2009" and resolve_model(world, layer).cutoff_dbm == -80.0
    assert resolve_channel(world, layer).loss_settings == {"rate": 0.1}  # the file's channel replaces the world's
    assert resolve_channel(world, None).latency_s == 0.5
    assert resolve_channel(None, None).ideal
    p.write_text("channel: {loss: {model: independent, rate: 2}}\n")
    with pytest.raises(ConfigError, match="probability"):
        load_wireless_file(p)


def test_the_best_route_maximises_the_product_of_the_hops_qualities():
    from usarsim.sim.routing import best_route

    q = {("a", "r1"): 0.9, ("r1", "b"): 0.9, ("a", "r2"): 0.99, ("r2", "r3"): 0.99, ("r3", "b"): 0.99, ("a", "c"): 0.5}

    def quality(x, y):
        return q.get((x, y)) or q.get((y, x))

    nodes = ["a", "b", "c", "r1", "r2", "r3"]
    # three hops at 0.99 (0.970) beat two at 0.9 (0.81)
    assert best_route("a", "b", nodes, quality) == ["a", "r2", "r3", "b"]
    q[("r2", "r3")] = 0.5
    assert best_route("a", "b", nodes, quality) == ["a", "r1", "b"]
    assert best_route("a", "z", nodes + ["z"], quality) is None
    assert best_route("a", "a", nodes, quality) == ["a"]
    q[("c", "b")] = 1e-4  # too weak a hop to route through
    assert best_route("c", "b", ["b", "c"], quality) is None
