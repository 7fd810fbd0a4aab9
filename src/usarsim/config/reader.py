"""Strict reading of YAML mappings into typed values, with errors that name the
file, the key path, the value received and what is allowed."""

from __future__ import annotations

import builtins
import dataclasses
import difflib
import math
import re
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import yaml  # type: ignore[import-untyped]  # PyYAML ships no type information (no types-PyYAML here)

from usarsim.errors import ConfigError


def load_yaml(path: str | Path) -> dict:
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"cannot read file ({exc.strerror})", path=str(p)) from exc
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise ConfigError(f"not valid YAML{where}: {getattr(exc, 'problem', exc)}", path=str(p)) from exc
    if not isinstance(data, dict):
        raise ConfigError("the file must hold a mapping of keys (name: ..., ...)", path=str(p))
    return data


# How alike (difflib's ratio) a key found must be to a required key that is missing to be
# reported as its misspelling: 'centre' and 'center' score 0.83, 'sise' and 'size' 0.75,
# two different keys such as 'step_run' and 'step_rise' 0.71.
MISSPELLING_CUTOFF = 0.75


def did_you_mean(word: str, allowed: Iterable[str]) -> str:
    allowed = list(allowed)
    close = difflib.get_close_matches(word, allowed, n=1, cutoff=0.6)
    if not close:
        lowered = {a.lower(): a for a in allowed}
        if word.lower() in lowered:
            close = [lowered[word.lower()]]
    hint = f" (did you mean '{close[0]}'?)" if close else ""
    return f"{hint}; allowed: {', '.join(sorted(allowed))}"


class FieldDefaults:
    """The defaults a dataclass declares, by field name: ``FieldDefaults(RobotConfig).battery_s``.

    Loaders read every optional key with the default of the field it fills
    (``top.float("battery_s", d.battery_s, min=...)``), so the dataclass is the one place a
    default is written.  A ``default_factory`` gives a fresh value; a field without a
    default, or a name that is no field, is a programming error (AttributeError)."""

    def __init__(self, cls: type):
        if not (isinstance(cls, type) and dataclasses.is_dataclass(cls)):
            raise TypeError(f"FieldDefaults needs a dataclass, got {cls!r}")
        self._cls = cls
        self._fields = {f.name: f for f in dataclasses.fields(cls)}

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        f = self._fields.get(name)
        if f is None:
            raise AttributeError(f"{self._cls.__name__} has no field '{name}'{did_you_mean(name, self._fields)}")
        if f.default is not dataclasses.MISSING:
            return f.default
        if f.default_factory is not dataclasses.MISSING:
            return f.default_factory()
        raise AttributeError(f"{self._cls.__name__}.{name} has no default: read it as a required key")


class Section:
    """A mapping being read; every key must be consumed or it is reported as unknown.

    Its readers are named after the types they return (``str``, ``float``, ``int``, ``bool``,
    ``list``), which hide those types inside the class body: its annotations spell them
    ``builtins.str`` and so on."""

    def __init__(self, data: Any, *, path: str, key: str = ""):
        self.path = path
        self.key = key
        if not isinstance(data, dict):
            raise ConfigError(f"expected a mapping, got {type(data).__name__} {data!r}", path=path, key=key or None)
        self.data = data
        self._used: set[str] = set()

    def _k(self, name: str) -> str:
        return f"{self.key}.{name}" if self.key else name

    def error(self, name: str, message: str) -> ConfigError:
        return ConfigError(message, path=self.path, key=self._k(name))

    def has(self, name: str) -> bool:
        return name in self.data

    def raw(self, name: str, default: Any = ..., *, required: bool = False) -> Any:
        self._used.add(name)
        if name in self.data:
            return self.data[name]
        if required or default is ...:
            typo = self.misspelling_of(name)
            if typo is not None:
                raise self.error(typo, f"unknown key '{typo}' (did you mean '{name}'?); '{name}' is required")
            raise self.error(name, "required key is missing")
        return default

    def has_read(self, name: str) -> bool:
        """Whether a key of this name was read (by any of the readers below)."""
        return name in self._used

    def misspelling_of(self, name: str) -> str | None:
        """The key of this mapping that looks like a misspelling of the missing key ``name``:
        one nothing has read yet, as close to it as difflib finds 'centre' to 'center'."""
        unread = [str(k) for k in self.data if k not in self._used]
        by_lower = {k.lower(): k for k in unread}
        if name.lower() in by_lower:
            return by_lower[name.lower()]
        close = difflib.get_close_matches(name.lower(), list(by_lower), n=1, cutoff=MISSPELLING_CUTOFF)
        return by_lower[close[0]] if close else None

    def str(self, name: str, default: Any = ..., *, choices: Iterable[str] | None = None) -> str:
        v = self.raw(name, default)
        if v is default and default is not ...:
            return v
        if not isinstance(v, str) or not v.strip():
            raise self.error(name, f"expected a non-empty text, got {v!r}")
        if choices is not None:
            choices = list(choices)
            if v not in choices:
                raise self.error(name, f"'{v}' is not allowed{did_you_mean(v, choices)}")
        return v

    def float(
        self,
        name: builtins.str,
        default: Any = ...,
        *,
        min: builtins.float | None = None,
        max: builtins.float | None = None,
        min_exclusive: builtins.bool = False,
    ) -> builtins.float:
        v = self.raw(name, default)
        if v is default and default is not ...:
            return v
        return check_float(v, self.path, self._k(name), min=min, max=max, min_exclusive=min_exclusive)

    def int(self, name: builtins.str, default: Any = ..., *, min: builtins.int | None = None) -> builtins.int:
        v = self.raw(name, default)
        if v is default and default is not ...:
            return v
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.error(name, f"expected an integer, got {v!r}")
        if min is not None and v < min:
            raise self.error(name, f"must be >= {min}, got {v}")
        return v

    def bool(self, name: builtins.str, default: Any = ...) -> builtins.bool:
        v = self.raw(name, default)
        if not isinstance(v, bool):
            raise self.error(name, f"expected true or false, got {v!r}")
        return v

    def vec(
        self, name: builtins.str, n: builtins.int = 3, default: Any = ..., *, positive: builtins.bool = False
    ) -> tuple[builtins.float, ...]:
        v = self.raw(name, default)
        if v is default and default is not ...:
            return v
        return check_vec(v, n, self.path, self._k(name), positive=positive)

    def section(self, name: builtins.str, default: Any = ...) -> Section:
        v = self.raw(name, default)
        return Section(v if v is not None else {}, path=self.path, key=self._k(name))

    def list(self, name: builtins.str, default: Any = ...) -> builtins.list[Any]:
        v = self.raw(name, default)
        if v is None:
            return []
        if not isinstance(v, list):
            raise self.error(name, f"expected a list, got {type(v).__name__}")
        return v

    def entries(self, name: builtins.str, *, required: builtins.bool = False) -> Iterator[Section]:
        """Each mapping of the list ``name`` (none when the key is missing, unless
        ``required``) as a Section keyed ``name[i]``; its unknown keys are refused once the
        loop's body has read it."""
        for i, raw in enumerate(self.list(name) if required else self.list(name, [])):
            s = Section(raw, path=self.path, key=f"{self._k(name)}[{i}]")
            yield s
            s.finish()

    def finish(self, allowed_extra: Iterable[builtins.str] = ()) -> None:
        """Fail on the first key that nothing read."""
        known = self._used | set(allowed_extra)
        for k in self.data:
            if k not in known:
                raise self.error(str(k), f"unknown key '{k}'{did_you_mean(str(k), known)}")


def check_float(
    v: Any, path: str, key: str, *, min: float | None = None, max: float | None = None, min_exclusive: bool = False
) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ConfigError(f"expected a number, got {v!r}", path=path, key=key)
    f = float(v)
    if not math.isfinite(f):
        raise ConfigError(f"expected a finite number, got {v!r}", path=path, key=key)
    if min is not None and (f < min or (min_exclusive and f == min)):
        op = ">" if min_exclusive else ">="
        raise ConfigError(f"must be {op} {min}, got {f}", path=path, key=key)
    if max is not None and f > max:
        raise ConfigError(f"must be <= {max}, got {f}", path=path, key=key)
    return f


def check_vec(v: Any, n: int, path: str, key: str, *, positive: bool = False) -> tuple[float, ...]:
    if not isinstance(v, (list, tuple)) or len(v) != n:
        raise ConfigError(f"expected a list of {n} numbers, got {v!r}", path=path, key=key)
    out = tuple(check_float(x, path, f"{key}[{i}]") for i, x in enumerate(v))
    if positive and any(x <= 0 for x in out):
        raise ConfigError(f"every value must be > 0, got {list(out)}", path=path, key=key)
    return out


# What an entry of a list of a world or robot file is called in an error: the key that gives
# its kind (a box, a RangeScanner) and the word used when that key is absent.
ENTRY_KINDS = {
    "objects": ("shape", "object"),
    "sensors": ("type", "item"),
    "chassis": ("shape", "box"),
    "shapes": ("shape", "box"),
    "wheels": (None, "wheel"),
    "links": (None, "link"),
    "start_poses": (None, "start pose"),
    "path_nodes": (None, "path node"),
    "victims": (None, "victim"),
    "false_alarms": (None, "false alarm"),
    "rfid_tags": (None, "RFID tag"),
    "water": (None, "water volume"),
    "lights": (None, "light"),
    "mission_packages": (None, "mission package"),
    "legs": (None, "leg"),
}
_KEY_TOKEN = re.compile(r"([^.\[\]]+)|\[(\d+)\]")


def describe_entry(entry: Any, list_key: str) -> str | None:
    """How an error names an entry of the list ``list_key``: ``box 'wall_north'``,
    ``RangeScanner 'Scanner1'``, ``start pose 'Start1'``, ``a box`` (no name); None when the
    entry is no mapping."""
    if not isinstance(entry, dict):
        return None
    kind_key, word = ENTRY_KINDS.get(list_key, ("type", "entry"))
    kind = entry.get(kind_key) if kind_key else None
    kind = kind if isinstance(kind, str) and kind.strip() else word
    name = entry.get("name", entry.get("id") if list_key == "rfid_tags" else None)
    if isinstance(name, (str, int)) and not isinstance(name, bool) and str(name).strip():
        return f"{kind} '{name}'"
    return f"a {kind}"


def name_entries(err: ConfigError, data: Any) -> ConfigError:
    """Name the list entries along ``err.key`` (the file's mapping is ``data``), so that an
    error deep in a list says which object it is about, not only its index:
    ``objects[12].centre: unknown key ... (objects[12] is box 'wall_north')``, or
    ``sensors[3] (RangeScanner 'Scanner1'): ...`` when the key is the entry itself.  Changes
    the text of ``err`` only (its key and message stay); returns it."""
    if not err.key or getattr(err, "entries_named", False):
        return err
    node, path, list_key, named = data, "", "", []
    for m in _KEY_TOKEN.finditer(err.key):
        word, index = m.group(1), m.group(2)
        if word is not None:
            node = node.get(word) if isinstance(node, dict) else None
            path, list_key = (f"{path}.{word}" if path else word), word
        else:
            if not isinstance(node, list) or int(index) >= len(node):
                break
            node, path = node[int(index)], f"{path}[{index}]"
            desc = describe_entry(node, list_key)
            if desc is not None and not (desc.endswith("'") and desc[desc.index("'") :] in err.message):
                named.append((path, desc))  # (unless the message names it already)
    if not named:
        return err
    where = f"{err.path}: " if err.path else ""
    last_path, last_desc = named[-1]
    if last_path == err.key:  # the error is about the entry itself
        named.pop()
        text = f"{where}{err.key} ({last_desc}): {err.message}"
    else:
        text = f"{where}{err.key}: {err.message}"
    if named:
        text += " (" + "; ".join(f"{p} is {d}" for p, d in named) + ")"
    err.args = (text,)
    err.entries_named = True  # type: ignore[attr-defined]  # a mark set here only, read back above
    return err
