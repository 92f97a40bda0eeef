"""MQTT: each panel's daemon is a client of a broker (Mosquitto, EMQX, HiveMQ, a cluster).

* :class:`~dsfd.integrations.mqtt.publisher.MqttPublisher` — state per cycle, availability with
  a last will, daily KPIs and Home Assistant discovery, sent from the database beside the
  loop (``dsfd run`` with an ``mqtt:`` section); its client also takes the commands on
  ``<base>/cmd/...`` (:mod:`~dsfd.integrations.mqtt.commands`: payloads,
  :mod:`~dsfd.integrations.mqtt.receiver`: into the daemon's ``commands`` table);
* :mod:`~dsfd.integrations.mqtt.fleet` — ``dsfd fleet``: one line per panel on a broker;
* :mod:`~dsfd.integrations.mqtt.broker` — a local Mosquitto for benchmarks and tests.

paho-mqtt 2.x is the optional extra ``dsfd[mqtt]``: :func:`publisher_for_run` raises
:class:`~dsfd.integrations.mqtt.link.MissingExtraError` naming the install command without it.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from dsfd.integrations.mqtt.link import MissingExtraError, require_paho, resolve_link

if TYPE_CHECKING:
    from dsfd.config import PanelConfig
    from dsfd.integrations.mqtt.publisher import MqttPublisher

__all__ = ["MissingExtraError", "publisher_for_run"]


def publisher_for_run(cfg: PanelConfig, *, config_path: Path, version: str) -> MqttPublisher:
    """The publisher of a panel with an ``mqtt:`` section, checked before anything opens.

    Raises :class:`MissingExtraError` without paho-mqtt 2.x, and
    :class:`~dsfd.config.ConfigError` naming the key path of a missing password or TLS file.
    """
    require_paho()
    link = resolve_link(cfg, config_path=config_path)
    from dsfd.integrations.mqtt.publisher import MqttPublisher

    return MqttPublisher(link, cfg, version=version)
