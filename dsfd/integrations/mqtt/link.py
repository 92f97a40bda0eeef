"""The connection to the broker: settings resolved at start, paho clients, reconnect backoff.

:func:`resolve_link` turns the ``mqtt:`` section into a :class:`BrokerLink` when ``dsfd run``
starts (before any device is opened): the password and TLS files are found and read, and a
missing one is a :class:`~dsfd.config.ConfigError` naming its key path. :func:`require_paho`
raises :class:`MissingExtraError` naming ``pip install 'dsfd[mqtt]'`` when paho-mqtt is not
installed. :func:`new_client` builds a paho-mqtt 2.x client (``CallbackAPIVersion.VERSION2``,
MQTT 3.1.1, no automatic reconnect: the publisher owns its reconnect policy).

Notes
-----
paho-mqtt 2.x API as documented in its ``client.py`` (2.2.0): ``Client(callback_api_version,
client_id, clean_session, protocol, reconnect_on_failure)``, ``username_pw_set``, ``tls_set(
ca_certs, certfile, keyfile)``, ``will_set(topic, payload, qos, retain)``, ``connect`` (blocking
TCP connect and CONNECT, bounded by ``connect_timeout``), ``loop_start``/``loop_stop`` (the
network thread), ``on_connect(client, userdata, flags, reason_code, properties)``,
``on_publish(client, userdata, mid, reason_code, properties)`` after the PUBACK of a QoS-1
message.

Backoff: exponential with "equal jitter" — the delay doubles per failed attempt up to a cap
and a uniformly random half of it is drawn, so a fleet of panels that lost the same broker
does not reconnect in lockstep (M. Brooker, "Exponential Backoff And Jitter", AWS
Architecture Blog, 2015).
"""

from __future__ import annotations

import os
import random
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from dsfd.config import ConfigError, ConfigIssue, PanelConfig
from dsfd.config.mqtt import Mqtt

if TYPE_CHECKING:
    from paho.mqtt.client import Client

__all__ = [
    "INSTALL_HINT",
    "Backoff",
    "BrokerLink",
    "MissingExtraError",
    "TlsFiles",
    "new_client",
    "parse_broker",
    "read_password_file",
    "require_paho",
    "resolve_file",
    "resolve_link",
]

INSTALL_HINT = "pip install 'dsfd[mqtt]'"


class MissingExtraError(RuntimeError):
    """paho-mqtt (the ``mqtt`` extra) is not installed."""


def require_paho() -> None:
    """Raise :class:`MissingExtraError` naming the install command if paho-mqtt 2.x is missing."""
    try:
        import paho.mqtt.client as mqtt
    except ImportError:
        raise MissingExtraError(
            f"MQTT needs the paho-mqtt library, which is not installed: {INSTALL_HINT}"
        ) from None
    if not hasattr(mqtt, "CallbackAPIVersion"):
        raise MissingExtraError(f"MQTT needs paho-mqtt 2.x (found an older one): "
                                f"{INSTALL_HINT}")


@dataclass(frozen=True)
class TlsFiles:
    ca_file: Path | None
    cert_file: Path | None
    key_file: Path | None


@dataclass(frozen=True)
class BrokerLink:
    """Where and how to connect, with the files already read (password not shown in repr)."""

    host: str
    port: int
    client_id: str
    username: str | None = None
    password: str | None = field(default=None, repr=False)
    tls: TlsFiles | None = None
    keepalive_s: int = 60

    @property
    def address(self) -> str:
        return f"{self.host}:{self.port}"


def resolve_file(name: str, *, config_dir: Path) -> Path:
    """Where a file named in the ``mqtt:`` section is: absolute as given; relative in
    ``$CREDENTIALS_DIRECTORY`` (systemd ``LoadCredential=``) if set, else in ``config_dir``."""
    path = Path(name).expanduser()
    if path.is_absolute():
        return path
    creds = os.environ.get("CREDENTIALS_DIRECTORY", "")
    return (Path(creds) if creds else config_dir) / path


def read_password_file(path: Path) -> str:
    """The password in ``path``: its first line (a trailing newline is not part of it)."""
    text = path.read_text(encoding="utf-8")
    lines = text.splitlines()
    if not lines or not lines[0]:
        raise ValueError("the file is empty (the password is its first line)")
    return lines[0]


def resolve_link(cfg: PanelConfig, *, config_path: Path) -> BrokerLink:
    """The broker link of a panel with an ``mqtt:`` section; files are checked and read.

    Raises :class:`ConfigError` naming ``mqtt.password_file`` or ``mqtt.tls.*`` when a file is
    missing or unreadable.
    """
    mq = settings_of(cfg)
    config_dir = config_path.resolve().parent
    issues: list[ConfigIssue] = []
    password = None
    if mq.password_file is not None:
        path = resolve_file(mq.password_file, config_dir=config_dir)
        try:
            password = read_password_file(path)
        except (OSError, ValueError, UnicodeDecodeError) as exc:
            issues.append(ConfigIssue("mqtt.password_file", mq.password_file,
                                      f"cannot read the password from {path}: {_why(exc)}"))
    tls = None
    if mq.tls is not None:
        found: dict[str, Path | None] = {}
        for key in ("ca_file", "cert_file", "key_file"):
            name = getattr(mq.tls, key)
            found[key] = None if name is None else resolve_file(name, config_dir=config_dir)
            where = found[key]
            if where is not None and not os.access(where, os.R_OK):
                issues.append(ConfigIssue(f"mqtt.tls.{key}", name,
                                          f"{where}: not found or not readable"))
        tls = TlsFiles(**found)
    if issues:
        raise ConfigError(issues, str(config_path))
    return BrokerLink(host=mq.host, port=mq.broker_port(), client_id=mq.client_id_for(
        cfg.panel.id), username=mq.username, password=password, tls=tls,
        keepalive_s=mq.keepalive_s)


def _why(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    return str(exc)


def parse_broker(text: str, *, default_port: int = 1883) -> tuple[str, int]:
    """``HOST[:PORT]`` (IPv6 as ``[::1]:1883``) → (host, port); ValueError if malformed."""
    host, port = text.strip(), default_port
    if host.startswith("["):
        end = host.find("]")
        if end < 0:
            raise ValueError(f"{text!r}: unclosed '[' in an IPv6 address")
        rest, host = host[end + 1:], host[1:end]
        if rest:
            if not rest.startswith(":"):
                raise ValueError(f"{text!r}: expected ':PORT' after the address")
            port = _port(rest[1:], text)
    elif host.count(":") == 1:
        host, _, number = host.partition(":")
        port = _port(number, text)
    if not host:
        raise ValueError(f"{text!r}: no host")
    return host, port


def _port(number: str, text: str) -> int:
    if not number.isdigit() or not 1 <= int(number) <= 65535:
        raise ValueError(f"{text!r}: the port must be a number 1..65535")
    return int(number)


def new_client(link: BrokerLink, *, client_id: str | None = None,
               connect_timeout_s: float = 5.0) -> Client:
    """A paho-mqtt 2.x client for ``link`` (not connected; no automatic reconnect)."""
    import paho.mqtt.client as mqtt

    client = mqtt.Client(callback_api_version=mqtt.CallbackAPIVersion.VERSION2,
                         client_id=link.client_id if client_id is None else client_id,
                         clean_session=True, protocol=mqtt.MQTTv311,
                         reconnect_on_failure=False)
    client.connect_timeout = connect_timeout_s
    if link.username is not None:
        client.username_pw_set(link.username, link.password)
    if link.tls is not None:
        t = link.tls
        client.tls_set(ca_certs=_str(t.ca_file), certfile=_str(t.cert_file),
                       keyfile=_str(t.key_file))
    return client


def _str(path: Path | None) -> str | None:
    return None if path is None else str(path)


@dataclass
class Backoff:
    """Reconnect delays: doubling from ``min_s`` to ``max_s``, each drawn from its upper half."""

    min_s: float
    max_s: float
    uniform: Callable[[float, float], float] = field(default=random.uniform, repr=False)
    attempts: int = 0

    def next_delay(self) -> float:
        """The delay before the next attempt [s]; call after each failed attempt."""
        cap = min(self.max_s, self.min_s * 2.0 ** min(self.attempts, 60))
        self.attempts += 1
        return self.uniform(cap / 2.0, cap)

    def reset(self) -> None:
        """After a successful connection."""
        self.attempts = 0


def settings_of(cfg: PanelConfig) -> Mqtt:
    """The panel's ``mqtt:`` section (which must be present)."""
    if cfg.mqtt is None:
        raise ValueError("the panel has no mqtt: section")
    return cfg.mqtt


def reason_text(reason: Any) -> str:
    """A paho reason code or error as the text a person reads in the log."""
    text = str(reason)
    return {"Not authorized": "not authorised",
            "Bad user name or password": "bad user name or password",
            "Unspecified error": "the connection broke"}.get(text, text)
