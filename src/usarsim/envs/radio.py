"""The team's radios on the simulator's own ComServer (protocol.md 12.1, docs/wireless.md): the
environments' team messages go as every robot's do, over the ComServer's links, which open only
while the simulator's radio model says a link holds, and through the server's channel
(capacity, loss, delay).  The signal between two robots is asked of it too (``GETSS``)."""

from __future__ import annotations

from collections.abc import Callable, Sequence

from usarsim.client import ClientError
from usarsim.client.radio import Radio, RadioError, link
from usarsim.config.world import WirelessConfig


def radio_model(world_wireless: WirelessConfig | None, model: str | None = None, config_file: str | None = None):
    """The radio model (:class:`usarsim.sim.radio.RadioModel`) a simulator started with
    ``--wireless-model model`` and ``--wireless-config config_file`` on a world with this
    ``wireless`` section uses, resolved by the simulator's own code; its ``holds(dBm)``
    says whether a link with that signal carries messages."""
    from usarsim.sim.radiomodels import resolve_model  # configuration only: no MuJoCo
    from usarsim.sim.wireless_file import load_wireless_file

    layer = load_wireless_file(config_file).radio if config_file else None
    return resolve_model(world_wireless, layer, model=model)


class TeamRadio:
    """A :class:`~usarsim.client.radio.Radio` for each of ``names`` (robots spawned by this
    client) on the ComServer at ``host``:``port``.  A message sent goes on the open links of
    its sender; what arrives is read after the simulation has stepped."""

    def __init__(self, host: str, port: int, names: Sequence[str], timeout: float = 10.0):
        self.radios: dict[str, Radio] = {}
        try:
            for name in names:
                self.radios[name] = Radio(host, port, name, timeout=timeout)
        except RadioError as exc:
            self.close()
            raise ClientError(f"{exc}; was the simulator started with its wireless servers?") from exc

    def signals(self, agents: Sequence[str]) -> dict[tuple[str, str], float | None]:
        """The signal strength (dBm) between each pair of ``agents`` now (None where the
        ComServer cannot tell): each agent asks of its later teammates in one write, all
        before any answer is read."""
        out: dict[tuple[str, str], float | None] = {}
        asks = [(a, list(agents[i + 1 :])) for i, a in enumerate(agents)]
        try:
            for a, later in asks:
                self.radios[a].ask_signals(later)
            for a, later in asks:
                out.update(((a, b), v) for b, v in zip(later, self.radios[a].read_signals(later), strict=True))
        except (RadioError, OSError) as exc:
            raise ClientError(f"the ComServer: {exc}") from exc
        return out

    def link_up(self, signals: dict[tuple[str, str], float | None], holds: Callable[[float], bool]) -> None:
        """Open a link for each pair whose signal holds and that has none open."""
        for (a, b), dbm in signals.items():
            if dbm is not None and holds(dbm) and b not in self.radios[a].links:
                try:
                    link(self.radios[a], self.radios[b])
                except RadioError as exc:
                    raise ClientError(str(exc)) from exc

    def send(self, src: str, payload: bytes) -> None:
        """``payload`` from ``src`` to each teammate it has a link with."""
        self.radios[src].broadcast(payload)

    def receive(self, agents: Sequence[str]) -> dict[str, list[tuple[str, bytes]]]:
        """What each of ``agents`` received since the last call: (sender, payload) in order."""
        return {a: self.radios[a].poll() for a in agents}

    def leave(self, agent: str) -> None:
        """``agent`` is done: its links close and its radio goes."""
        radio = self.radios.pop(agent, None)
        if radio is not None:
            radio.close()
        for r in self.radios.values():
            r.forget(agent)

    def close(self) -> None:
        for r in self.radios.values():
            r.close()
        self.radios = {}
