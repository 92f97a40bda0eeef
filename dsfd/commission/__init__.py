"""Commissioning: the point-to-point check-out of a panel's wiring before the controller runs.

``dsfd commission --signals`` reads every configured signal several times and checks what a
person would (:mod:`dsfd.commission.checks`); ``--stroke`` moves every actuator through its
range and back (:mod:`dsfd.commission.stroke`). Both talk to the devices through the daemon's
own drivers, without the control loop, and leave a record (:mod:`dsfd.commission.record`).
docs/commissioning.md is the user's guide.
"""

from __future__ import annotations

from dsfd.commission.checks import Conditions, Finding
from dsfd.commission.record import latest_record, write_record

__all__ = ["Conditions", "Finding", "latest_record", "write_record"]
