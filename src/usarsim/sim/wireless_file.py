"""Wireless configuration files (``usarsim serve --wireless-config FILE``): USARSim's
USARComServer.ini (manual 3.2.4.2) with this project's extensions, or a YAML file holding a
world file's ``wireless`` section, the channel included (docs/wireless.md)."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

from usarsim.config.reader import did_you_mean
from usarsim.config.world import WIRELESS_KEYS, WirelessConfig
from usarsim.errors import ConfigError
from usarsim.sim.radio import RADIO_MODELS, model_names, resolve_channel, resolve_model

# Extensions of this project accepted beside the ComConnection keys of WIRELESS_KEYS.
_INI_EXTRA = {"Model": "model", "CacheDistance": "cache_distance_m", "maxcachedist": "cache_distance_m"}
_INI_SERVER = ("ListenPort", "iListenPort", "bDebug")
_SECTION_RE = re.compile(r"\[([^\]]*)\]\Z")


@dataclass(frozen=True)
class WirelessFile:
    """What a USARComServer.ini-style file sets: the radio model (its constants as a
    :class:`WirelessConfig` layer), the ComServer's ``ListenPort``, the ComServerInterface's
    ``iListenPort`` and whether any ``bDebug`` is on."""

    radio: WirelessConfig
    listen_port: int | None = None
    interface_port: int | None = None
    debug: bool = False


def load_wireless_file(path: str | Path) -> WirelessFile:
    """A wireless configuration file: a YAML file (``.yaml``, ``.yml``) holds a world file's
    ``wireless`` section (alone, or under a ``wireless`` key), the channel included; any other
    file is read as USARSim's ini (:func:`load_wireless_ini`)."""
    if str(path).lower().endswith((".yaml", ".yml")):
        return _load_wireless_yaml(str(path))
    return load_wireless_ini(path)


def _load_wireless_yaml(path: str) -> WirelessFile:
    from usarsim.config.reader import Section, load_yaml
    from usarsim.config.world_sections import read_wireless

    data = load_yaml(path)
    if isinstance(data, dict) and set(data) == {"wireless"}:
        data = data["wireless"]
    if not isinstance(data, dict):
        raise ConfigError("expected the keys of a world's wireless section (model, eCutoff, channel, ...)", path=path)
    layer = read_wireless(Section(data, path=path, key="wireless"))
    try:
        resolve_model(layer)
        resolve_channel(layer)
    except (ValueError, ConfigError) as exc:
        raise ConfigError(str(exc), path=path) from None
    return WirelessFile(layer)


def load_wireless_ini(path: str | Path) -> WirelessFile:
    """Read an ini-style file as USARSim's USARComServer.ini (manual 3.2.4.2): ``[Section]``
    headers (any, or none), ``Key=Value`` lines, ``;`` and ``#`` comments; keys in any case.
    Keys: ListenPort, bDebug, ePdo, eDo, eN, eCutoff, eMaxObs, eAttenFac, plus ``Model``
    (waf, waf2009, distance, perfect), ``CacheDistance`` (alias ``maxcachedist``, metres)
    and ``iListenPort`` (the ComServerInterface's port).  An unknown key, or a value that
    is not a number where one is needed, is an error naming the file, the line and the key."""
    path = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise ConfigError(f"cannot read the wireless configuration: {exc.strerror}", path=path) from None
    known = {k.lower(): k for k in (*WIRELESS_KEYS, *_INI_EXTRA, *_INI_SERVER)}
    values: dict[str, object] = {}
    listen = interface = None
    debug = False
    for no, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line[0] in ";#" or _SECTION_RE.match(line):
            continue
        where = f"line {no}"
        if "=" not in line:
            raise ConfigError(f"expected 'Key=Value', got {line[:80]!r}", path=path, key=where)
        key, _, value = (p.strip() for p in line.partition("="))
        name = known.get(key.lower())
        if name is None:
            raise ConfigError(f"unknown key '{key}'{did_you_mean(key, known.values())}", path=path, key=where)
        where = f"{where}: {name}"
        if name == "Model":
            if value.lower() not in RADIO_MODELS:
                raise ConfigError(
                    f"'{value}' is not a radio model{did_you_mean(value.lower(), model_names())}",
                    path=path,
                    key=where,
                )
            values["model"] = value.lower()
        elif name == "bDebug":
            if value.lower() not in ("true", "false", "1", "0"):
                raise ConfigError(f"expected True or False, got {value!r}", path=path, key=where)
            debug = debug or value.lower() in ("true", "1")
        elif name in ("ListenPort", "iListenPort"):
            if not value.isdigit() or not 0 <= int(value) <= 65535:
                raise ConfigError(f"expected a port number 0..65535, got {value!r}", path=path, key=where)
            if name == "ListenPort":
                listen = int(value)
            else:
                interface = int(value)
        else:
            field = WIRELESS_KEYS.get(name) or _INI_EXTRA[name]
            try:
                number = float(value)
            except ValueError:
                number = math.nan
            if field == "max_walls" and value.lower() in ("none", ""):
                number = -1.0
            if not math.isfinite(number):
                raise ConfigError(f"expected a number, got {value!r}", path=path, key=where)
            values[field] = int(number) if field == "max_walls" else number
    layer = WirelessConfig(**values)  # type: ignore[arg-type]  # each value read for its field above
    try:  # the constants' ranges, as RadioModel checks them
        resolve_model(layer)
    except (ValueError, ConfigError) as exc:
        raise ConfigError(str(exc), path=path) from None
    return WirelessFile(layer, listen, interface, debug)
