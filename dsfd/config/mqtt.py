"""Settings of the optional connection to an MQTT broker (Home Assistant, a BMS, ``dsfd fleet``).

YAML shape (the ``mqtt:`` section of a panel file; absent or ``null``: no MQTT)::

    mqtt:
      host: broker.example.org
      port: null                  # null: 1883, or 8883 with tls
      tls:                        # absent: plain TCP
        ca_file: ca.pem           # null: the system's trusted CAs
        cert_file: null           # client certificate and key for mutual TLS
        key_file: null
      username: dsfd-suwon-south
      password_file: mqtt-password   # relative: in $CREDENTIALS_DIRECTORY (LoadCredential=)
      client_id: null             # default dsfd-<panel id>
      base_topic: null            # default dsfd/<panel id>
      discovery_prefix: homeassistant   # null: no Home Assistant discovery
      keepalive_s: 60
      backlog_max_age_h: 24

The password is never written into the panel file (it is world-readable, docs/mqtt.md):
``password_file`` names a file holding it. Relative file names (the password, the TLS files)
are looked up in ``$CREDENTIALS_DIRECTORY`` when it is set (systemd's ``LoadCredential=``),
else next to the panel file; :mod:`dsfd.integrations.mqtt.link` resolves and reads them when
``dsfd run`` starts, naming the key path if one is missing.

Topic names follow MQTT 3.1.1 (OASIS, 2014), section 4.7: UTF-8, ``/``-separated levels, no
wildcards (``+``, ``#``) in a name that is published to, and no leading ``$`` (reserved for
the broker).
"""

from __future__ import annotations

from dataclasses import dataclass

from dsfd.config.loader import Problem, setting

__all__ = ["DEFAULT_DISCOVERY_PREFIX", "Mqtt", "MqttTls", "topic_problem"]

DEFAULT_DISCOVERY_PREFIX = "homeassistant"
PLAIN_PORT = 1883
TLS_PORT = 8883


def topic_problem(topic: str) -> str:
    """Why ``topic`` cannot be a topic name dsfd publishes under ('' if it can)."""
    if not topic:
        return "must not be empty"
    if any(c in topic for c in "+#\0"):
        return "must not contain the wildcards '+', '#' (or NUL)"
    if topic.startswith("$"):
        return "must not start with '$' (reserved for the broker's own topics)"
    if topic.startswith("/") or topic.endswith("/") or "//" in topic:
        return "must not start or end with '/' nor contain an empty level"
    if len(topic.encode("utf-8")) > 1024:
        return "is too long (at most 1024 bytes here; MQTT allows 65535 for the whole name)"
    return ""


@dataclass(frozen=True, kw_only=True)
class MqttTls:
    """TLS towards the broker (port 8883 by default)."""

    ca_file: str | None = setting(
        None, doc="CA certificate(s) the broker's certificate must chain to (PEM); null: the "
        "system's trusted CAs. Relative: in $CREDENTIALS_DIRECTORY, else next to the panel file")
    cert_file: str | None = setting(
        None, doc="Client certificate (PEM) for brokers that authenticate clients by "
        "certificate; needs key_file")
    key_file: str | None = setting(None, doc="Private key of cert_file (PEM)")

    def check(self) -> list[Problem]:
        if (self.cert_file is None) != (self.key_file is None):
            key = "key_file" if self.key_file is None else "cert_file"
            return [Problem(key, None, "cert_file and key_file go together (a client "
                            "certificate needs its private key)")]
        return []


@dataclass(frozen=True, kw_only=True)
class Mqtt:
    """The panel's MQTT client: state out, Home Assistant discovery, commands in."""

    host: str = setting(doc="Host name or address of the broker (or of the broker cluster's "
                        "load balancer)")
    port: int | None = setting(
        None, doc="TCP port; null: 1883, or 8883 with tls", ge=1, le=65535)
    tls: MqttTls | None = setting(None, doc="TLS settings; null: plain TCP")
    username: str | None = setting(None, doc="User name at the broker; null: anonymous")
    password_file: str | None = setting(
        None, doc="File holding the password (one line). Relative: in $CREDENTIALS_DIRECTORY "
        "(systemd LoadCredential=), else next to the panel file")
    password: str | float | None = setting(
        None, doc="Not allowed: a password never goes into the panel file; use password_file")
    client_id: str | None = setting(
        None, doc="MQTT client identifier, unique on the broker; null: dsfd-<panel id>")
    base_topic: str | None = setting(
        None, doc="Topic prefix of this panel's messages (<base>/state, <base>/availability, "
        "<base>/kpi, <base>/cmd/...); null: dsfd/<panel id>")
    discovery_prefix: str | None = setting(
        DEFAULT_DISCOVERY_PREFIX, doc="Home Assistant's MQTT discovery prefix; null: publish "
        "no discovery configs")
    keepalive_s: int = setting(
        60, doc="MQTT keep-alive: the broker declares the connection dead (and publishes the "
        "last will, availability 'offline') after 1.5 times this without traffic", unit="s",
        ge=5, le=3600)
    backlog_max_age_h: float = setting(
        24.0, doc="After a broker outage or a restart, state messages of cycles older than "
        "this (relative to the newest stored cycle) are not sent", unit="h", gt=0, le=24 * 31)
    reconnect_min_s: float = setting(
        1.0, doc="First delay before reconnecting; it doubles per failed attempt (with "
        "random jitter) up to reconnect_max_s", unit="s", gt=0, le=600)
    reconnect_max_s: float = setting(
        120.0, doc="Longest delay between reconnection attempts", unit="s", gt=0, le=3600)

    def check(self) -> list[Problem]:
        out: list[Problem] = []
        if self.password is not None:  # the value is never echoed: the file is world-readable
            out.append(Problem("password", "<hidden>", "a password never goes into the panel "
                               "file: write it to a file (e.g. a systemd credential) and name "
                               "that file in password_file"))
        if not self.host.strip():
            out.append(Problem("host", self.host, "must not be empty"))
        if self.password_file is not None and self.username is None:
            out.append(Problem("password_file", self.password_file,
                               "a password needs a username"))
        for key in ("base_topic", "discovery_prefix"):
            value = getattr(self, key)
            if value is not None and (why := topic_problem(value)):
                out.append(Problem(key, value, why))
        cid = self.client_id
        if cid is not None and (not cid or len(cid) > 128 or any(c.isspace() for c in cid)):
            out.append(Problem("client_id", cid, "1 to 128 characters without spaces"))
        if self.reconnect_min_s > self.reconnect_max_s:
            out.append(Problem("reconnect_min_s", self.reconnect_min_s,
                               f"must not exceed reconnect_max_s ({self.reconnect_max_s:g})"))
        return out

    def broker_port(self) -> int:
        """The port to connect to [-]."""
        if self.port is not None:
            return self.port
        return TLS_PORT if self.tls is not None else PLAIN_PORT

    def client_id_for(self, panel_id: str) -> str:
        return self.client_id if self.client_id is not None else f"dsfd-{panel_id}"

    def base_topic_for(self, panel_id: str) -> str:
        return self.base_topic if self.base_topic is not None else f"dsfd/{panel_id}"
