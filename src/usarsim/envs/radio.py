"""The signal between two robots, asked of the simulator's own ComServer (``GETSS a b;``,
protocol.md 12.1): the environments carry a team message only when the simulator's radio
model says the link holds."""

from __future__ import annotations

import socket
import time
from collections.abc import Sequence

from usarsim.client import ClientError, ClientTimeout
from usarsim.config.world import WirelessConfig
from usarsim.protocol.wireless import (
    CommandSplitter,
    WcsFail,
    WcsGetSS,
    WcsOk,
    WcsRegister,
    WcsSignal,
    format_wcs_request,
    parse_wcs_reply,
)


def radio_model(world_wireless: WirelessConfig | None, model: str | None = None, config_file: str | None = None):
    """The radio model (:class:`usarsim.sim.radio.RadioModel`) a simulator started with
    ``--wireless-model model`` and ``--wireless-config config_file`` on a world with this
    ``wireless`` section uses, resolved by the simulator's own code; its ``holds(dBm)``
    says whether a link with that signal carries messages."""
    from usarsim.sim.radiomodels import resolve_model  # configuration only: no MuJoCo
    from usarsim.sim.wireless_file import load_wireless_file

    layer = load_wireless_file(config_file).radio if config_file else None
    return resolve_model(world_wireless, layer, model=model)


class SignalMeter:
    """A ComServer connection that registered ``names`` (robots spawned by this client) and
    asks GETSS for pairs of them, all pairs of a call in one write."""

    def __init__(self, host: str, port: int, names: Sequence[str], timeout: float = 10.0):
        self.timeout = timeout
        try:
            self.sock = socket.create_connection((host, port), timeout=timeout)
        except OSError as exc:
            raise ClientError(
                f"cannot connect to the ComServer at {host}:{port} ({exc}); was the simulator "
                "started with its wireless servers?"
            ) from exc
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._split = CommandSplitter()
        self._replies: list[str] = []
        ip = self.sock.getsockname()[0]  # GETSS is answered only to a robot's own address
        self._send([WcsRegister(n, ip) for n in names])
        for name, reply in zip(names, self._read(len(names))):
            if not isinstance(reply, WcsOk):
                raise ClientError(f"the ComServer refused REGISTER {name}: {getattr(reply, 'reason', reply)}")

    def _send(self, cmds: list) -> None:
        try:
            self.sock.sendall("".join(format_wcs_request(c) for c in cmds).encode("ascii"))
        except OSError as exc:
            raise ClientError(f"the ComServer closed the connection ({exc})") from exc

    def _read(self, n: int) -> list:
        deadline = time.monotonic() + self.timeout
        while len(self._replies) < n:
            left = deadline - time.monotonic()
            if left <= 0:
                raise ClientTimeout(
                    f"ComServer: {n - len(self._replies)} of {n} replies did not arrive within {self.timeout:g} s"
                )
            self.sock.settimeout(left)
            try:
                data = self.sock.recv(1 << 16)
            except TimeoutError:
                continue
            except OSError as exc:
                raise ClientError(f"the ComServer closed the connection ({exc})") from exc
            if not data:
                raise ClientError("the ComServer closed the connection")
            self._replies += self._split.feed(data)
        out, self._replies = self._replies[:n], self._replies[n:]
        return [parse_wcs_reply(r) for r in out]

    def strengths(self, pairs: Sequence[tuple[str, str]]) -> list[float | None]:
        """The signal strength in dBm between each pair of robots, now (None where the
        ComServer cannot tell, e.g. a robot that has left the world)."""
        if not pairs:
            return []
        self._send([WcsGetSS(a, b) for a, b in pairs])
        out: list[float | None] = []
        for reply in self._read(len(pairs)):
            if isinstance(reply, WcsSignal):
                out.append(reply.dbm)
            elif isinstance(reply, WcsFail):
                out.append(None)
            else:
                raise ClientError(f"the ComServer answered GETSS with {reply!r}")
        return out

    def close(self) -> None:
        try:
            self.sock.close()
        except OSError:
            pass
