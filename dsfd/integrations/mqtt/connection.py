"""One connection attempt of the publisher: the paho client and what its callbacks report.

paho-mqtt's network thread (``loop_start``) calls the callbacks; they only record what
happened and wake the publisher's thread (CallbackAPIVersion.VERSION2 signatures: paho-mqtt
2.x ``client.py``). A command message is handed to the
:class:`~dsfd.integrations.mqtt.receiver.CommandReceiver`'s queue and nothing else happens
to it here: nothing a callback does may block or raise into paho's thread.
"""

from __future__ import annotations

import contextlib
import queue
import threading
from typing import TYPE_CHECKING, Any

from dsfd.integrations.mqtt.link import reason_text

if TYPE_CHECKING:
    from paho.mqtt.client import Client

    from dsfd.integrations.mqtt.receiver import CommandReceiver

__all__ = ["Connection"]


class Connection:
    """One connection attempt: the paho client and what its callbacks report."""

    def __init__(self, client: Client, wake: threading.Event,
                 receiver: CommandReceiver) -> None:
        self.client = client
        self.connack = threading.Event()
        self.lost = threading.Event()
        self.refused: str = ""
        self.lost_reason: str = ""
        #: The broker's answer to the command subscription: "" granted, else why not.
        self.subscription: str | None = None
        self.acks: queue.SimpleQueue[int] = queue.SimpleQueue()
        client.on_connect = self._on_connect
        client.on_disconnect = self._on_disconnect
        client.on_publish = self._on_publish
        client.on_subscribe = self._on_subscribe
        client.on_message = self._on_message
        self._wake = wake
        self._receiver = receiver

    # paho's network thread calls these (CallbackAPIVersion.VERSION2 signatures)
    def _on_connect(self, _c: Any, _u: Any, _flags: Any, reason_code: Any, _p: Any) -> None:
        if reason_code.is_failure:
            self.refused = reason_text(reason_code)
        self.connack.set()

    def _on_disconnect(self, _c: Any, _u: Any, _flags: Any, reason_code: Any, _p: Any) -> None:
        self.lost_reason = reason_text(reason_code)
        self.lost.set()
        self.connack.set()
        self._wake.set()

    def _on_publish(self, _c: Any, _u: Any, mid: int, _reason: Any, _p: Any) -> None:
        self.acks.put(mid)
        self._wake.set()

    def _on_subscribe(self, _c: Any, _u: Any, _mid: int, reason_codes: Any, _p: Any) -> None:
        refused = [reason_text(r) for r in reason_codes if r.is_failure]
        self.subscription = ", ".join(refused)
        self._wake.set()

    def _on_message(self, _c: Any, _u: Any, message: Any) -> None:
        # A command message: queued for the receiver's thread, never handled here; nothing
        # may escape into paho's network thread (a topic that is not UTF-8, say).
        with contextlib.suppress(Exception):
            self._receiver.offer(message.topic, message.payload, message.retain)
