"""Integrations at the edge: they read what the daemon stores and never sit on the cycle's path.

* :mod:`dsfd.integrations.mqtt` — state, daily KPIs and Home Assistant discovery over MQTT,
  and the ``dsfd fleet`` view.
* :mod:`dsfd.integrations.bacnet` — the panel as a BACnet/IP device of the building's control
  system, commanded through priority arrays (docs/bacnet.md).
"""
