"""Small details of the wire that real clients read (protocol.md 5.4, 6.5)."""

from __future__ import annotations

from pathlib import Path

from usarsim.config.catalog import ROBOTS_DIR

OMNI_ITEM = "  - {type: OmniCam, name: Omni, location: [0.0, 0.0, -0.3]}\n"


def test_an_omnicam_zoom_is_answered_with_its_own_type(server_factory, test_world, tmp_path):
    """``SET {Type OmniCam} {Opcode Zoom}`` is answered ``RES ... {Type OmniCam} ...`` (not
    ``{Type Camera}``): an omnidirectional camera has no zoom, so the status is Failed."""
    text = (Path(ROBOTS_DIR) / "P2AT.yaml").read_text().replace("class_name: P2AT", "class_name: OmniP2AT")
    robots = tmp_path / "robots"
    robots.mkdir()
    (robots / "OmniP2AT.yaml").write_text(text.rstrip("\n") + "\n" + OMNI_ITEM)
    srv = server_factory(world=test_world, seed=3, robot_dirs=(str(robots),))
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.OmniP2AT} {Name R} {Location -6,0,-0.3} {Rotation 0,0,0}")
    c.step(0.2)
    c.send("SET {Type OmniCam} {Name Omni} {Opcode Zoom} {Params 0.5}")
    c.send("SET {Type Camera} {Name Camera} {Opcode Zoom} {Params 0.5}")
    res = [ln.text for ln in c.step(0.2) if ln.text.startswith("RES")]  # lock-step: at the next STEP
    assert res == [
        "RES {Time 0.20} {Type OmniCam} {Name Omni} {FOV 6.2832} {Status Failed}",
        "RES {Time 0.20} {Type Camera} {Name Camera} {FOV 0.5000} {Status OK}",
    ], res
