"""Messages declared once: each field of a message's dataclass says how it is printed and read
back, and both the format and the parser follow from that.

A field is one of:

* :func:`key`: one ``{Key value}`` segment of a kind of value (:class:`Kind`: its printed
  form, 2 or 4 decimals, an integer, ``True``/``False``, text, a vector; and how it is read
  back).  Written always, or only when not None (``optional``); read from the first segment
  of that key, or its ``absent`` value when the line lacks it (else the line is refused).
* :func:`pairs`: ``{name value}`` segments of the names no key of the message has (STA's
  flipper angles), printed where the field stands.
* :func:`packed`: items each in one segment, ``{Name F1 Range 4.2}`` (sonars, encoders,
  touch sensors).
* :func:`group`: repeated groups, each opened by its first key (``{Link n} {Value v}
  {Torque t}``), declared as a small dataclass of keys, every one required of a group but
  those the message gives a value when absent (``group(PackageLink, LINK, torque=0.0)``); its last
  field may itself be a group (a mission package's links, after its name).

* :func:`joined`: several fields of a reading in one segment, ``{Pose x,y,theta}``.
* ``FIELD`` pairs: an item's free-form fields (CONF, EFF, RES), printed as USARSim did.
* :func:`items`: a reading's repeated groups, its item class's keys named beside it.

A reading sent in several layouts is :class:`Variants` (the first layout whose test holds).
``fixed`` segments (``{Type AerialVehicle}``) follow the message's word.  :func:`message`
compiles a class's layout once: its format is one function written for it (as
:mod:`dataclasses` writes its methods), as fast as one written by hand; its parser reads a
:class:`~usarsim.protocol.messages.common._Reader`, whose errors name the message.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from ..grammar import RawMessage, Segment
from .common import _CRLF, _groups, _Reader
from .kinds import Kind, _number

WIRE = "usarsim.wire"  # the metadata key of a declared field


@dataclass(frozen=True, slots=True)
class Key:
    """One ``{Key value}`` segment (see the module's text)."""

    wire: str
    kind: Kind
    optional: bool = False
    absent: Any = None  # the value of a line that lacks the key, when it has one (has_absent)
    has_absent: bool = False


@dataclass(frozen=True, slots=True)
class Pairs:
    """``{name value}`` segments of names the message's keys do not have."""

    kind: Kind


@dataclass(frozen=True, slots=True)
class Packed:
    """Items each in one segment, ``{Name n Range v}`` (UT's packed layout); the separate
    layout ``{Name n} {Range v}`` of UDK lines is read too.  ``cls``: an item, built from its
    name and its value (its first two fields)."""

    cls: type
    wire: str
    kind: Kind
    more: tuple[tuple[str, Kind], ...] = ()  # further fields in the segment (an item's GEO: Orientation, Mount)


@dataclass(frozen=True, slots=True)
class Group:
    """Repeated groups of keys, each a ``cls``; ``defaults`` of keys this message may lack;
    ``keys``: the cls's fields and their keys where the cls carries no protocol (a reading's
    items), in the wire order."""

    cls: type
    defaults: tuple[tuple[str, Any], ...] = ()
    keys: tuple[tuple[str, Key | Pairs], ...] | None = None


@dataclass(frozen=True, slots=True)
class Joined:
    """Several fields in one segment, comma-separated (the odometry's ``{Pose x,y,theta}``)."""

    wire: str
    kind: Kind
    fields: tuple[str, ...]


def key_spec(wire: str, kind: Kind, *, optional: bool = False, absent: Any = dataclasses.MISSING) -> Key:
    """A :class:`Key` (``optional`` and ``absent`` as :func:`key`'s), for a layout's ``keys``
    where the class carries no protocol of its own (a reading, a message's payload)."""
    has_absent = optional or absent is not dataclasses.MISSING
    return Key(wire, kind, optional, None if absent is dataclasses.MISSING else absent, has_absent)


def key(
    wire: str,
    kind: Kind,
    *,
    default: Any = dataclasses.MISSING,
    optional: bool = False,
    absent: Any = dataclasses.MISSING,
) -> Any:
    """A field sent as ``{wire value}``; ``optional``: left out of the line when None (and
    None when a line lacks it); ``absent``: the value of a line that lacks it (a key without
    either is required of a line, whatever the dataclass's ``default``)."""
    return dataclasses.field(default=default, metadata={WIRE: key_spec(wire, kind, optional=optional, absent=absent)})


def pairs(kind: Kind) -> Any:
    """A field of ``(name, value)`` pairs sent as ``{name value}`` segments."""
    return dataclasses.field(default=(), metadata={WIRE: Pairs(kind)})


def group(cls: type, keys: Mapping[str, Key] | None = None, **defaults: Any) -> Any:
    """A field of repeated groups, each a ``cls`` (a dataclass of :func:`key` fields whose first
    opens it, or, for a class that carries no protocol, of the fields ``keys`` names)."""
    spec = Group(cls, tuple(defaults.items()), None if keys is None else tuple(keys.items()))
    return dataclasses.field(default=(), metadata={WIRE: spec})


def items(cls: type, **keys: Key | Pairs) -> Group:
    """A reading's field of repeated groups, each a ``cls`` of :mod:`usarsim.readings` (which
    carries no protocol): ``keys`` name its fields and their keys, the first opening a group."""
    return Group(cls, (), tuple(keys.items()))


def joined(wire: str, kind: Kind, *fields: str) -> Joined:
    """A reading's ``fields`` sent together as ``{wire a,b,c}``, each printed as ``kind``."""
    return Joined(wire, kind, fields)


def _group_keys(spec: Group) -> list[tuple[str, Any, Any]]:
    return [(n, k, None) for n, k in spec.keys] if spec.keys is not None else _declared(spec.cls)


def _packed_segment(r: _Reader, seg: Segment, field: str) -> tuple[str, str]:
    """``{Name n Field v}`` -> (n, v)."""
    tokens = seg.value.split()
    if len(tokens) != 3 or tokens[1].lower() != field.lower():
        raise r.error(seg.key, seg.value, f"'name {field} value'")
    return tokens[0], tokens[2]


def _named(r: _Reader, field: str) -> list[tuple[str, Segment]]:
    """Items of packed (``{Name n Field v}``) or separate (``{Name n} {Field v}``) layout."""
    out: list[tuple[str, Segment]] = []
    pending: str | None = None
    for s in r.raw.segments:
        k = s.key.lower()
        if k == "name":
            if len(s.value.split()) == 1:
                pending = s.value
            else:
                name, value = _packed_segment(r, s, field)
                out.append((name, Segment(field, value)))
        elif k == field.lower() and pending is not None:
            out.append((pending, s))
            pending = None
    return out


@functools.cache  # a class's declarations do not change: read once, not at every line parsed
def _declared(cls: type) -> list[tuple[str, Any, dataclasses.Field[Any]]]:
    return [(f.name, f.metadata[WIRE], f) for f in dataclasses.fields(cls) if WIRE in f.metadata]


def _read_key(r: _Reader, k: Key, absent: Any = dataclasses.MISSING) -> Any:
    """A key's value from the line (its first segment), else its value when absent, else missing."""
    wanted = k.wire.lower()
    may_lack = absent is not dataclasses.MISSING or k.has_absent
    for seg in r.raw.segments:
        if seg.key.lower() == wanted:
            if may_lack and k.kind.read is _number:
                # a number a line may lack is named in errors as declared (FrontSteer, not frontsteer)
                seg = Segment(k.wire, seg.value)
            return k.kind.read(r, seg, k.wire)
    if absent is not dataclasses.MISSING:
        return absent
    if k.has_absent:
        return k.absent
    raise r.missing(k.wire)


class Layout:
    """A message's declared fields, compiled once: its format and its parser."""

    def __init__(
        self,
        cls: type,
        word: str,
        fixed: tuple[tuple[str, str], ...] = (),
        read_first: tuple[str, ...] = (),
        wire_first: tuple[str, ...] = (),
        keys: Mapping[str, Key | Pairs | Packed | Group | Joined] | None = None,
        end: str = _CRLF,
        constants: dict[str, Any] | None = None,
        nested: dict[str, type] | None = None,
    ):
        self.cls = cls
        self.word = word
        self.fixed = fixed
        self.end = end
        self.constants = dict(constants or {})  # fields a parsed message of this layout always has
        # a field that is a payload of its own (a STA's RobotStatus): its fields are named
        # "status.battery_s" in ``keys``, and read into an instance of its class
        self.nested = dict(nested or {})
        declared = _declared(cls) if keys is None else [(name, k, None) for name, k in keys.items()]
        by_name = {name: (name, spec, f) for name, spec, f in declared}
        # the wire order: the field order, but for fields a positional dataclass must keep
        # elsewhere (``wire_first``: sent first)
        self.fields = [by_name[n] for n in wire_first] + [e for e in by_name.values() if e[0] not in wire_first]
        # the order fields are read in (which error a line with several faults gets)
        self.read_order = [by_name[n] for n in read_first] + [e for e in self.fields if e[0] not in read_first]
        self.own = frozenset(
            spec.wire.lower() for _, spec, _ in self.fields if isinstance(spec, (Key, Joined))
        ) | frozenset(w.lower() for w, _ in fixed)
        self.format: Callable[[Any], str] = self._compile_format()

    # ---- formatting
    def _compile_format(self) -> Callable[[Any], str]:
        env: dict[str, Any] = {}
        lines = ["def format(m):"]
        run: list[str] = []  # a run of segments always written: one % format
        args: list[str] = []
        head = self.word + "".join(" {%s %s}" % (w, v) for w, v in self.fixed)

        def flush(first: bool = False) -> None:
            text = (head if first else "") + "".join(run)
            if args:
                lines.append(f"    s {'=' if first else '+='} {text!r} % ({', '.join(args)},)")
            else:
                lines.append(f"    s {'=' if first else '+='} {text!r}")
            run.clear()
            args.clear()

        started = False

        def value_of(name: str, kind: Kind, expr: str) -> str:
            if kind.fmt is None:
                return expr
            ident = "fmt_" + name.replace(".", "_")
            env[ident] = kind.fmt
            return f"{ident}({expr})"

        for name, spec, _ in self.fields:
            if isinstance(spec, Key) and not spec.optional and spec.kind.empty is None:
                run.append(" {%s %s}" % (spec.wire, spec.kind.spec))
                args.append(value_of(name, spec.kind, f"m.{name}"))
                continue
            if isinstance(spec, Joined):
                run.append(" {%s %s}" % (spec.wire, ",".join([spec.kind.spec] * len(spec.fields))))
                args += [value_of(f, spec.kind, f"m.{f}") for f in spec.fields]
                continue
            flush(first=not started)
            started = True
            if isinstance(spec, Key) and spec.kind.empty is not None:
                lines += [
                    f"    if m.{name}:",
                    f"        s += ' {{{spec.wire} {spec.kind.spec}}}' % {value_of(name, spec.kind, f'm.{name}')}",
                    "    else:",
                    f"        s += {' {%s%s}' % (spec.wire, spec.kind.empty)!r}",
                ]
            elif isinstance(spec, Key):
                lines += [
                    f"    if m.{name} is not None:",
                    f"        s += ' {{{spec.wire} {spec.kind.spec}}}' % {value_of(name, spec.kind, f'm.{name}')}",
                ]
            elif isinstance(spec, Pairs):
                Layout._emit_pairs(lines, value_of, spec, f"m.{name}", name, "    ")
            elif isinstance(spec, Packed):
                item_fields = [f.name for f in dataclasses.fields(spec.cls)[: 2 + len(spec.more)]]
                wires = ((spec.wire, spec.kind), *spec.more)
                text = "".join(f" {w} {k.spec}" for w, k in wires)
                vals = ", ".join(value_of(f"{name}_{f}", k, f"i.{f}") for f, (_, k) in zip(item_fields[1:], wires))
                lines += [
                    f"    for i in m.{name}:",
                    f"        s += ' {{Name %s{text}}}' % (i.{item_fields[0]}, {vals})",
                ]
            else:  # a group
                self._emit_group(lines, value_of, spec, f"m.{name}", name, 1)
        flush(first=not started)
        lines.append(f"    return s + {self.end!r}" if self.end else "    return s")
        exec("\n".join(lines), env)  # noqa: S102  (the text above, from the declarations only)
        fn: Callable[[Any], str] = env["format"]
        return fn

    @staticmethod
    def _emit_pairs(
        lines: list[str], value_of: Callable[[str, Kind, str], str], spec: Pairs, pairs: str, name: str, pad: str
    ) -> None:
        """The lines that write ``{name value}`` for every pair (``{name}`` for an empty value
        of a kind that has an empty form)."""
        lines.append(f"{pad}for n, v in {pairs}:")
        if spec.kind.empty is None:
            lines.append(f"{pad}    s += ' {{%s {spec.kind.spec}}}' % (n, {value_of(name, spec.kind, 'v')})")
        else:
            lines += [
                f"{pad}    x = {value_of(name, spec.kind, 'v')}",
                f"{pad}    s += ' {{%s {spec.kind.spec}}}' % (n, x) if x else ' {{%s{spec.kind.empty}}}' % n",
            ]

    @staticmethod
    def _emit_group(
        lines: list[str], value_of: Callable[[str, Kind, str], str], spec: Group, items: str, name: str, depth: int
    ) -> None:
        """The lines that write every group of ``items`` (a group inside runs nested)."""
        pad = "    " * depth
        var = f"g{depth}"
        lines.append(f"{pad}for {var} in {items}:")
        run: list[str] = []
        args: list[str] = []

        def flush() -> None:
            if run:
                fmt = "".join(run)
                lines.append(f"{pad}    s += {fmt!r} % ({', '.join(args)},)" if args else f"{pad}    s += {fmt!r}")
            run.clear()
            args.clear()

        for sub, sk, _ in _group_keys(spec):
            if isinstance(sk, Key) and sk.optional:  # left out when None; an empty value: {Key}
                flush()
                value = value_of(f"{name}_{sub}", sk.kind, f"{var}.{sub}")
                lines.append(f"{pad}    if {var}.{sub} is not None:")
                if sk.kind.empty is None:
                    lines.append(f"{pad}        s += ' {{{sk.wire} {sk.kind.spec}}}' % {value}")
                else:
                    lines += [
                        f"{pad}        s += ' {{{sk.wire} {sk.kind.spec}}}' % {value} if {var}.{sub} else "
                        + repr(" {%s%s}" % (sk.wire, sk.kind.empty))
                    ]
            elif isinstance(sk, Key):
                run.append(" {%s %s}" % (sk.wire, sk.kind.spec))
                args.append(value_of(f"{name}_{sub}", sk.kind, f"{var}.{sub}"))
            elif isinstance(sk, Pairs):
                flush()
                Layout._emit_pairs(lines, value_of, sk, f"{var}.{sub}", f"{name}_{sub}", pad + "    ")
            else:
                flush()
                Layout._emit_group(lines, value_of, sk, f"{var}.{sub}", f"{name}_{sub}", depth + 1)
        flush()

    # ---- parsing
    def parse(self, r: _Reader) -> Any:
        """The message of a line already known to be this one's (its word checked, and its
        variant chosen when a word has several)."""
        values: dict[str, Any] = dict(self.constants)
        for name, spec, _ in self.read_order:
            if isinstance(spec, Key):
                values[name] = _read_key(r, spec)
            elif isinstance(spec, Joined):
                values.update(zip(spec.fields, r.vector(spec.wire, r.text(spec.wire), len(spec.fields))))
            elif isinstance(spec, Pairs):
                values[name] = tuple(
                    (s.key, spec.kind.read(r, s, s.key)) for s in r.raw.segments if s.key.lower() not in self.own
                )
            elif isinstance(spec, Packed):
                values[name] = tuple(spec.cls(n, spec.kind.read(r, seg, spec.wire)) for n, seg in _named(r, spec.wire))
            else:
                values[name] = self._read_groups(r, spec)
        for field, cls in self.nested.items():
            head = field + "."
            inner = {n[len(head) :]: values.pop(n) for n in list(values) if n.startswith(head)}
            values[field] = cls(**inner)
        return self.cls(**values)

    def _read_groups(self, r: _Reader, spec: Group, segments: tuple[Segment, ...] | None = None) -> tuple[Any, ...]:
        """The groups of ``segments`` (the line's by default).  A group's keys are read from its
        segments before a group inside it starts; the groups inside are read first."""
        keys = _group_keys(spec)
        defaults = dict(spec.defaults)
        inner = [(name, k) for name, k, _ in keys if isinstance(k, Group)]
        inner_start = _group_keys(inner[0][1])[0][1].wire.lower() if inner else None
        out = []
        for found in _groups(r.raw.segments if segments is None else segments, keys[0][1].wire):
            own = [s for s in found if s.key.lower() not in self.own]
            cut = next((i for i, s in enumerate(own) if i > 0 and s.key.lower() == inner_start), len(own))
            values: dict[str, Any] = {name: self._read_groups(r, k, tuple(own[cut:])) for name, k in inner}
            gr = _Reader(RawMessage(r.raw.type, tuple(own[:cut])), r.what)
            for name, k, _ in keys:
                if isinstance(k, Key):
                    values[name] = _read_key(gr, k, defaults.get(name, dataclasses.MISSING))
            out.append(spec.cls(**values))
        return tuple(out)


def message(
    cls: type,
    word: str,
    *,
    fixed: tuple[tuple[str, str], ...] = (),
    read_first: tuple[str, ...] = (),
    wire_first: tuple[str, ...] = (),
) -> Layout:
    """The compiled layout of a declared message class, sent as ``word`` (then ``fixed``);
    ``read_first``: fields read before the others (so that a line with several faults is
    refused for the one clients have always been told of first); ``wire_first``: fields sent
    first, where the dataclass's order (kept for positional arguments) is not the wire's."""
    return Layout(cls, word, fixed, read_first, wire_first)


def packed(cls: type, wire: str, kind: Kind, *more: tuple[str, Kind]) -> Packed:
    """Items of ``cls`` each in one ``{Name n wire value}`` segment (``more``: further
    ``(wire, kind)`` fields in it, ``{Name n Location l Orientation o Mount m}``)."""
    return Packed(cls, wire, kind, more)


def reading(
    cls: type,
    *,
    fixed: tuple[tuple[str, str], ...] = (),
    read_first: tuple[str, ...] = (),
    constants: dict[str, Any] | None = None,
    **keys: Key | Packed | Group | Joined,
) -> Layout:
    """The compiled layout of a SEN body (what follows ``SEN [{Time t}]``) for a reading class
    of :mod:`usarsim.readings`, which carries no protocol of its own: ``keys`` name its fields
    and their keys, in the wire order (after ``fixed``); ``read_first`` as :func:`message`'s;
    ``constants``: fields every reading read with this layout has (not on the wire)."""
    return Layout(cls, "", fixed, read_first, keys=keys, end="", constants=constants)


class Variants:
    """A reading sent in one of several layouts, the first whose test holds (a test of None
    always does): a GPS with a fix and without.  ``parse``: how a line is read back, one of
    the layouts' parsers or a rule of the sensor's own."""

    def __init__(
        self,
        cls: type,
        choices: tuple[tuple[Callable[[Any], bool] | None, Layout], ...],
        parse: Callable[[_Reader], Any],
    ):
        self.cls = cls
        self.choices = choices
        self.parse = parse

    def format(self, m: Any) -> str:
        for test, layout in self.choices:
            if test is None or test(m):
                return layout.format(m)
        raise TypeError(f"no layout of {self.cls.__name__} fits {m!r}")
