"""The simulated plant in a process of its own, for measuring the daemon alone.

A deployed daemon does not host the façade: ``dsfd bench daemon`` runs the truth plant
(:func:`dsfd.sim.daemon_plant.simulated_plant`) in a child process (``spawn``: the child
imports what the plant needs — SciPy's integrator among it — and nothing of the daemon's
memory is shared or copied), and the daemon talks to it through a pipe with the calls of
:class:`~dsfd.drivers.simulated.PlantLike`. The daemon process then holds what a deployed
daemon holds, and its resident memory and CPU time are the daemon's own.

A call that raises in the child raises the same exception type in the parent (the driver
turns plant failures into device errors, as in-process).
"""

from __future__ import annotations

import multiprocessing as mp
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from dsfd.drivers.simulated import SimulatedDriver

__all__ = ["PlantProcess", "RemoteCommand"]


@dataclass(frozen=True)
class RemoteCommand:
    """The command the plant executed, as the driver reads it back."""

    values: dict[str, float]

    def as_dict(self) -> dict[str, float]:
        return dict(self.values)


def _serve(conn: Any, kwargs: dict[str, Any]) -> None:
    """Child: build the plant, then answer calls until told to stop."""
    from dsfd.sim.daemon_plant import plant_options, simulated_plant

    fidelity = kwargs.pop("fidelity", None)
    if fidelity is not None:
        kwargs["options"] = plant_options(fidelity, kwargs["cfg"].model)
    sim = simulated_plant(**kwargs)
    plant = sim.plant
    conn.send(("ready", {"start_s": sim.start_s, "notes": sim.notes,
                         "command": plant.command.as_dict(), "time_s": plant.time_s}))
    while True:
        method, args = conn.recv()
        if method == "stop":
            usage = os.times()
            conn.send(("ok", {"cpu_s": usage.user + usage.system, "rss_mb": _rss_mb()}))
            return
        try:
            if method == "advance_and_read":
                ahead = args - plant.time_s
                if ahead > 1e-6:
                    plant.advance(ahead)
                out: Any = plant.read_sensors()
            elif method == "apply":
                out = plant.apply(args).as_dict()
            elif method == "advance":
                plant.advance(args)
                out = None
            elif method == "read_sensors":
                out = plant.read_sensors()
            elif method == "room_heat":
                out = (plant.room_heat_j(), (plant.time_s - sim.start_s) / 3600.0)
            else:
                raise ValueError(f"unknown plant call {method!r}")
            conn.send(("ok", (out, plant.time_s, plant.command.as_dict(), _rss_mb())))
        except Exception as exc:  # sent back and raised again in the parent
            conn.send(("error", (type(exc), str(exc))))


def _rss_mb() -> float:
    with open("/proc/self/statm", encoding="ascii") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


class PlantProcess:
    """The simulated plant in a child process (module docstring): a :class:`PlantLike` for
    the driver and a :class:`~dsfd.daemon.runner.PlantUnderTest` for :func:`serve`.

    Parameters are those of :func:`dsfd.sim.daemon_plant.simulated_plant` (keyword only),
    or ``fidelity`` (``full``/``lumped``) for its ``options``: the parent need not import the
    plant.
    Use as a context manager, or call :meth:`close`.
    """

    def __init__(self, **kwargs: Any) -> None:
        ctx = mp.get_context("spawn")
        self._conn, child = ctx.Pipe()
        self._proc = ctx.Process(target=_serve, args=(child, kwargs), daemon=True)
        self._proc.start()
        child.close()
        status, info = self._conn.recv()
        if status == "error":
            raise info[0](info[1])
        self.start_s: float = info["start_s"]
        self.notes: tuple[str, ...] = tuple(info["notes"])
        self._time_s: float = info["time_s"]
        self._command = RemoteCommand(info["command"])
        #: Largest resident memory of the plant process seen [MB], and its CPU time [s].
        self.rss_mb_max = 0.0
        self.cpu_s = float("nan")
        self._driver: SimulatedDriver | None = None

    def _call(self, method: str, args: Any = None) -> Any:
        self._conn.send((method, args))
        status, payload = self._conn.recv()
        if status == "error":
            raise payload[0](payload[1])
        out, self._time_s, command, rss = payload
        self._command = RemoteCommand(command)
        self.rss_mb_max = max(self.rss_mb_max, rss)
        return out

    @property
    def time_s(self) -> float:
        return self._time_s

    @property
    def command(self) -> RemoteCommand:
        return self._command

    def apply(self, command: Mapping[str, float]) -> RemoteCommand:
        return RemoteCommand(self._call("apply", dict(command)))

    def advance(self, seconds: float) -> None:
        self._call("advance", float(seconds))

    def read_sensors(self) -> dict[str, float]:
        return self._call("read_sensors")

    def advance_and_read(self, time_s: float) -> dict[str, float]:
        """Advance to ``time_s`` and read, in one round trip."""
        return self._call("advance_and_read", float(time_s))

    def room_heat(self) -> tuple[dict[str, float], float]:
        """Heat into the room since the start [J] by term, and the hours it covers [h]."""
        return self._call("room_heat")

    def room_heat_now(self) -> dict[str, float] | None:
        """Heat into the room since the start [J] by term; None while a call that the read
        budget abandoned is still in flight (one pipe, one caller at a time)."""
        return None if self.driver.busy else self.room_heat()[0]

    @property
    def driver(self) -> SimulatedDriver:
        """The daemon's driver of this plant (one per plant)."""
        if self._driver is None:
            self._driver = SimulatedDriver(self)
        return self._driver

    def close(self) -> None:
        """Stop the child (collecting its CPU time and memory) and wait for it."""
        if self._proc.is_alive():
            try:
                self._conn.send(("stop", None))
                _, info = self._conn.recv()
                self.cpu_s = info["cpu_s"]
                self.rss_mb_max = max(self.rss_mb_max, info["rss_mb"])
            except (EOFError, OSError):
                pass
            deadline = time.monotonic() + 10.0
            self._proc.join(max(0.0, deadline - time.monotonic()))
        if self._proc.is_alive():
            self._proc.terminate()
            self._proc.join()
        self._conn.close()

    def __enter__(self) -> PlantProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
