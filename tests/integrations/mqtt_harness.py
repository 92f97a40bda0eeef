"""A real Mosquitto broker for the MQTT tests, and mosquitto_sub/mosquitto_pub as the
third-party clients (Home Assistant, a BMS) that the daemon talks to.

The broker is Debian's ``mosquitto`` on a free loopback port with a password file
(:class:`dsfd.integrations.mqtt.broker.LocalBroker`); tests are skipped, saying why, only if
it is not installed. Time limits are hang guards.
"""

from __future__ import annotations

import json
import subprocess
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from dsfd.integrations.mqtt.broker import LocalBroker, find_mosquitto
from tests.daemon.harness import write_panel

#: Hang guard for waiting on messages [s].
MESSAGE_LIMIT_S = 60.0


def mosquitto_missing() -> str:
    """Why the broker tests cannot run here ('' if they can)."""
    missing = [n for n in ("mosquitto", "mosquitto_passwd", "mosquitto_sub", "mosquitto_pub")
               if find_mosquitto(n) is None]
    return (f"{', '.join(missing)} not installed (apt-get install mosquitto "
            "mosquitto-clients; .ci/run does)") if missing else ""


def mqtt_panel(path: Path, broker: LocalBroker, *, password: str | None = None,
               panel_id: str | None = None, mqtt: Mapping[str, Any] | None = None,
               extra: Mapping[str, Any] | None = None, tcp_port: int | None = None,
               station_port: str | None = None) -> Path:
    """A panel file publishing to ``broker``; the password in a file next to it. Without
    ``tcp_port`` it has no devices (a dry run); with it, the I/O module on that loopback port
    and the station on ``station_port`` (a HIL run)."""
    secret = path.with_name(path.stem + "-password")
    secret.write_text((broker.password if password is None else password) + "\n")
    section = {"host": "127.0.0.1", "port": broker.port, "username": broker.username,
               "password_file": secret.name, "reconnect_min_s": 0.5, "reconnect_max_s": 2.0,
               **(mqtt or {})}
    doc: dict[str, Any] = {"mqtt": section, **(extra or {})}
    if panel_id is not None:
        doc["panel"] = {"id": panel_id}
    return write_panel(path, devices=tcp_port is not None, tcp_port=tcp_port,
                       station_port=station_port, extra=doc)


def run_args(panel: Path, state: Path, *, start: str, cycles: int, speed: float) -> list[str]:
    return ["run", "--config", str(panel), "--dry-run", "--plant", "sim", "--plant-fidelity",
            "lumped", "--start", start, "--cycles", str(cycles), "--speed", str(speed),
            "--state-dir", str(state)]


@dataclass(frozen=True)
class Message:
    retained: bool
    topic: str
    payload: str

    def json(self) -> Any:
        return json.loads(self.payload)


class Subscriber:
    """``mosquitto_sub`` printing retain flag, topic and payload of every message to a file."""

    def __init__(self, broker: LocalBroker, *topics: str, out: Path,
                 persistent_id: str | None = None) -> None:
        cmd = [find_mosquitto("mosquitto_sub") or "mosquitto_sub", "-h", "127.0.0.1",
               "-p", str(broker.port), "-u", broker.username, "-P", broker.password,
               "-q", "1", "-F", "%r\t%t\t%p"]
        if persistent_id is not None:  # a persistent session: the broker queues for it
            cmd += ["-c", "-i", persistent_id]
        for t in topics:
            cmd += ["-t", t]
        self.cmd, self.out = cmd, out
        self.proc: subprocess.Popen[bytes] | None = None

    def start(self) -> Subscriber:
        self.proc = subprocess.Popen(self.cmd, stdout=self.out.open("wb"),
                                     stderr=subprocess.DEVNULL)
        time.sleep(0.3)  # the subscription is in place before anything is published
        return self

    def messages(self) -> list[Message]:
        out = []
        for line in self.out.read_text(errors="replace").splitlines():
            flag, topic, payload = ([*line.split("\t", 2), "", ""])[:3]
            out.append(Message(flag == "1", topic, payload))
        return out

    def wait_for(self, predicate: Callable[[list[Message]], bool], *,
                 limit_s: float = MESSAGE_LIMIT_S) -> list[Message]:
        deadline = time.monotonic() + limit_s
        while True:
            got = self.messages()
            if predicate(got):
                return got
            if time.monotonic() > deadline:
                raise AssertionError(f"messages did not arrive within {limit_s} s; got "
                                     f"{len(got)}: {[m.topic for m in got[-5:]]}")
            time.sleep(0.1)

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            self.proc.wait(10)


def state_keys(messages: list[Message], *, retained: bool = False) -> list[tuple[int, int]]:
    """(run, cycle) of the state messages in arrival order (live ones unless ``retained``)."""
    return [(m.json()["run"], m.json()["cycle"]) for m in messages
            if m.topic.endswith("/state") and m.retained == retained]
