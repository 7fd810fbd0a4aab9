"""Batched environments: ``num_envs`` worlds of ``usarsim/Explore-v0`` stepped together by a few
worker processes, each running its worlds' simulators in-process (the direct path), so that
the worlds use every processor (:class:`ExploreVectorEnv`, :func:`make_vector`).

A Gymnasium vector environment: observations, rewards and ends are stacked per world, infos
merged as Gymnasium merges them (each key with its ``_key`` mask); a world whose episode ended
starts its next one at its next step (Gymnasium's ``next_step`` autoreset: that step returns
the new episode's first observation, reward 0 and no end); ``reset(seed=s)`` seeds world ``i``
with ``s + i``, so that world ``i`` runs exactly the episodes a single :class:`ExploreEnv` reset
with ``s + i`` runs, bit for bit.

The worlds are shared among ``workers`` processes (by default one per processor, at most one
per world): each steps its worlds one after the other, writes their observations into one block
of shared memory and answers for all of them in one message.  Gymnasium's
:class:`~gymnasium.vector.AsyncVectorEnv` keeps a process per world; with four worlds on two
cores that made 1.1 to 1.4 times the env steps a second of one world, the processes taking
turns at every step.
"""

from __future__ import annotations

import math
import multiprocessing as mp
import os
import time
import traceback
from multiprocessing.connection import Connection
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space, iterate

from .explore import ExploreEnv

__all__ = ["ExploreVectorEnv", "make_vector"]

# How long a worker polls for the next command before it sleeps: longer than the main
# process's turn between two steps (a few tenths of a millisecond), so that the worker's
# processor is not given up (in a virtual machine, taken back by the host) at every step.
POLL_S = 0.002
# The thread counts of the BLAS libraries NumPy may be built with, read when they load.
BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


class _Slots:
    """Every world's observation in one block of shared memory: for each key of the Dict
    space, an array of (worlds, *shape) of its dtype, which the workers write and the main
    process copies out (no array is pickled on the way)."""

    def __init__(self, space: Any, worlds: int, buffer: Any):
        self.views: dict[str, np.ndarray] = {}
        offset = 0
        for key, shape, dtype in _layout(space):
            count = worlds * math.prod(shape)
            self.views[key] = np.frombuffer(buffer, dtype=dtype, count=count, offset=offset).reshape((worlds, *shape))
            offset += _aligned(count * dtype.itemsize)

    @staticmethod
    def nbytes(space: Any, worlds: int) -> int:
        return sum(_aligned(worlds * math.prod(shape) * dtype.itemsize) for _, shape, dtype in _layout(space))

    def write(self, world: int, obs: dict[str, np.ndarray]) -> None:
        for key, view in self.views.items():
            view[world] = obs[key]

    def read(self) -> dict[str, np.ndarray]:
        return {key: view.copy() for key, view in self.views.items()}


def _layout(space: Any) -> list[tuple[str, tuple[int, ...], np.dtype]]:
    """(key, shape, dtype) of each Box of a Dict observation space, in its order."""
    return [(key, tuple(box.shape or ()), np.dtype(box.dtype)) for key, box in space.spaces.items()]


def _aligned(n: int) -> int:
    return (n + 7) // 8 * 8


def _await(pipe: Connection, poll_s: float) -> None:
    """Poll ``pipe`` for up to ``poll_s`` seconds, giving the processor to anything else that
    wants it between looks (then :meth:`~Connection.recv` waits as usual)."""
    end = time.perf_counter() + poll_s
    while not pipe.poll(0) and time.perf_counter() < end:
        os.sched_yield()


def _worker(
    pipe: Connection,
    kwargs: dict[str, Any],
    count: int,
    core: int | None,
    buffer: Any,
    first: int,
    worlds: int,
) -> None:
    """A worker process: ``count`` worlds (``first`` to ``first + count - 1`` of ``worlds``),
    stepped as the main process asks; their observations go to the shared ``buffer``."""
    envs: list[ExploreEnv] = []
    if core is not None and hasattr(os, "sched_setaffinity"):
        try:
            os.sched_setaffinity(0, {core})
        except OSError:
            pass
    try:
        envs = [ExploreEnv(**kwargs) for _ in range(count)]
        slots = _Slots(envs[0].observation_space, worlds, buffer)
        ended = [False] * count
        pipe.send(("ready", None))
        while True:
            _await(pipe, POLL_S)
            command, data = pipe.recv()
            if command == "reset":
                seeds, options = data
                infos = []
                for k, (env, s) in enumerate(zip(envs, seeds)):
                    obs, info = env.reset(seed=s, options=options)
                    slots.write(first + k, obs)
                    infos.append((None, info))
                ended = [False] * count
                pipe.send(("ok", infos))
            elif command == "step":
                results = []
                for k, (env, action) in enumerate(zip(envs, data)):
                    if ended[k]:  # next_step autoreset: the new episode's first observation
                        obs, info = env.reset()
                        results.append((None, 0.0, False, False, info))
                        ended[k] = False
                    else:
                        obs, reward, terminated, truncated, info = env.step(action)
                        ended[k] = terminated or truncated
                        results.append((None, reward, terminated, truncated, info))
                    slots.write(first + k, obs)
                pipe.send(("ok", results))
            elif command == "close":
                break
    except (EOFError, KeyboardInterrupt):  # the main process is gone
        pass
    except Exception:
        try:
            pipe.send(("error", traceback.format_exc()))
        except OSError:
            pass
    finally:
        for env in envs:
            env.close()
        pipe.close()


class ExploreVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` :class:`ExploreEnv` worlds (``env_kwargs`` go to each; the direct path by
    default) in ``workers`` processes (see the module's text); with ``pin`` (Linux) the k-th
    worker keeps to the k-th processor this process may use: two workers on two cores then
    made 889 - 922 env steps a second of four worlds against 700 - 720 when the kernel moved
    them about (three runs each, alternately, 2026-11-29)."""

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(
        self,
        num_envs: int = 4,
        *,
        workers: int | None = None,
        context: str = "spawn",
        pin: bool = True,
        **env_kwargs: Any,
    ):
        if int(num_envs) < 1:
            raise ValueError(f"num_envs must be at least 1, got {num_envs!r}")
        self.num_envs = n = int(num_envs)
        allowed = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else []
        cores = len(allowed) or os.cpu_count() or 1
        w = min(n, max(1, cores if workers is None else int(workers)))
        kwargs = {"transport": "inproc", **env_kwargs}
        kwargs.setdefault("prelaunch", kwargs["transport"] != "inproc")
        probe = ExploreEnv(**kwargs)  # the spaces (and any mistake in the arguments, here)
        self.single_observation_space = probe.observation_space
        self.single_action_space = probe.action_space
        probe.close()
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)
        self._counts = [n // w + (1 if i < n % w else 0) for i in range(w)]
        ctx: Any = mp.get_context(context)  # a start method's context (its Process and Pipe)
        space = self.single_observation_space
        if not isinstance(space, gym.spaces.Dict):
            raise TypeError(f"an ExploreEnv's observations are a Dict space, got {space!r}")
        buffer = ctx.RawArray("B", max(8, _Slots.nbytes(space, n)))
        self._slots = _Slots(space, n, buffer)
        self._pipes: list[Connection] = []
        self.processes: list[Any] = []
        # a worker steps on one processor: one BLAS thread in it (the others spin beside it
        # after a call, making pinned steps 10 - 15 % slower), unless the caller chose the
        # number; a spawned worker starts with this environment (a forked one has its BLAS loaded)
        blas = {k: "1" for k in BLAS_THREADS if k not in os.environ}
        os.environ.update(blas)
        try:
            self._start_workers(ctx, kwargs, allowed if pin else [], buffer)
        finally:
            for k in blas:
                os.environ.pop(k, None)
        self.closed = False
        self._receive()  # every world built

    def _start_workers(self, ctx: Any, kwargs: dict[str, Any], allowed: list[int], buffer: Any) -> None:
        n, first = self.num_envs, 0
        for i, count in enumerate(self._counts):
            parent, child = ctx.Pipe()
            core = allowed[i % len(allowed)] if allowed else None
            proc = ctx.Process(
                target=_worker,
                args=(child, kwargs, count, core, buffer, first, n),
                name=f"usarsim-vector-{i}",
                daemon=True,
            )
            first += count
            proc.start()
            child.close()
            self._pipes.append(parent)
            self.processes.append(proc)

    def _receive(self) -> list[Any]:
        out = []
        for pipe in self._pipes:
            try:
                status, data = pipe.recv()
            except EOFError:
                self.close()
                raise RuntimeError("a worker of the vector environment ended unexpectedly") from None
            if status == "error":
                self.close()
                raise RuntimeError(f"a worker of the vector environment failed:\n{data}")
            if status == "ok":
                out.extend(data)
        return out

    def _split(self, values: list[Any]) -> list[list[Any]]:
        out, at = [], 0
        for count in self._counts:
            out.append(values[at : at + count])
            at += count
        return out

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None):
        if seed is None or isinstance(seed, int):
            seeds: list[int | None] = [None if seed is None else seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"{len(seeds)} seeds for {self.num_envs} worlds")
        for pipe, part in zip(self._pipes, self._split(seeds)):
            pipe.send(("reset", (part, options)))
        results = self._receive()
        return self._slots.read(), self._infos([info for _, info in results])

    def step(self, actions):
        for pipe, part in zip(self._pipes, self._split(list(iterate(self.action_space, actions)))):
            pipe.send(("step", part))
        results = self._receive()
        rewards = np.array([r[1] for r in results], dtype=np.float64)
        terminations = np.array([r[2] for r in results], dtype=np.bool_)
        truncations = np.array([r[3] for r in results], dtype=np.bool_)
        return (
            self._slots.read(),
            rewards,
            terminations,
            truncations,
            self._infos([r[4] for r in results]),
        )

    def _infos(self, infos: list[dict[str, Any]]) -> dict[str, Any]:
        """The worlds' infos merged as Gymnasium merges them (``_add_info``), when every world
        has the same keys (an ExploreEnv's always do): each key's values in an array, and
        its ``_key`` mask."""
        keys = infos[0].keys()
        if any(info.keys() != keys for info in infos):
            merged: dict[str, Any] = {}
            for i, info in enumerate(infos):
                merged = self._add_info(merged, info, i)
            return merged
        out: dict[str, Any] = {}
        everyone = np.ones(self.num_envs, dtype=np.bool_)
        for key in keys:
            values = [info[key] for info in infos]
            kind = type(values[0])
            if kind in (int, float, bool) and all(type(v) is kind for v in values):
                out[key] = np.array(values, dtype=kind)
            else:
                array = np.empty(self.num_envs, dtype=object)
                array[:] = [None] * self.num_envs
                for i, v in enumerate(values):
                    array[i] = v
                out[key] = array
            out[f"_{key}"] = everyone.copy()
        return out

    def close_extras(self, **kwargs: Any) -> None:
        for pipe in self._pipes:
            try:
                pipe.send(("close", None))
            except OSError:
                pass
        for proc in self.processes:
            proc.join(30)
            if proc.is_alive():
                proc.kill()
        for pipe in self._pipes:
            pipe.close()


def make_vector(num_envs: int = 4, **kwargs: Any) -> ExploreVectorEnv:
    """An :class:`ExploreVectorEnv` of ``num_envs`` worlds (``workers``, ``context`` and the
    :class:`ExploreEnv` arguments as keywords)."""
    return ExploreVectorEnv(num_envs, **kwargs)
