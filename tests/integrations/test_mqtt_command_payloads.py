"""MQTT command payloads as pure logic: topic + payload → the request ``dsfd override``/
``resume``/``mode`` would file, and the receiver's handling against a real database.

The expected requests are written from docs/mqtt.md's command table and Home Assistant's
documented payloads (a select publishes the option's text, a number its value — an integer
when whole —, a button its ``payload_press``), not from the code's output.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from dsfd.config import load_panel
from dsfd.daemon.commands import CommandError, OperatorCommand, validate_command
from dsfd.integrations.mqtt.commands import MAX_PAYLOAD_BYTES, SHOWN_BYTES, request_of, shown
from dsfd.integrations.mqtt.receiver import CommandReceiver, _Message
from dsfd.storage.timeseries import Store
from tests.conftest import PANELS

BASE = "dsfd/suwon-south"


@pytest.fixture(scope="module")
def cfg():
    return load_panel(PANELS / "suwon-south.yaml")


@pytest.mark.parametrize("subtopic, payload, expected", [
    ("override", '{"hold": "2h", "louver_deg": 36}',
     OperatorCommand("override", hold_s=7200.0, phi_deg=36.0)),
    ("override", "{}", OperatorCommand("override")),
    ("override", ' {"regime": 10, "hold": 90} ', OperatorCommand("override", hold_s=5400.0,
                                                                 afr=10, or_pct=0.0)),
    ("regime", "7: supply out→EB→IT→room", OperatorCommand("override", afr=7)),
    ("regime", "3", OperatorCommand("override", afr=3)),
    ("louver_deg", "-36", OperatorCommand("override", phi_deg=-36.0)),
    ("louver_deg", "54.0", OperatorCommand("override", phi_deg=54.0)),
    ("damper_pct", "40", OperatorCommand("override", or_pct=40.0)),
    ("resume", "resume", OperatorCommand("resume")),
    ("resume", "{}", OperatorCommand("resume")),
    ("mode", "cooling", OperatorCommand("mode", mode="cooling")),
    ("mode", '{"mode": "auto"}', OperatorCommand("mode", mode="auto")),
])
def test_command_payloads_become_the_requests_of_the_cli(cfg, subtopic, payload,
                                                         expected) -> None:
    assert validate_command(cfg, request_of(subtopic, payload.encode())) == expected


@pytest.mark.parametrize("subtopic, payload, field, words", [
    ("explode", "1", "topic", "unknown command"),
    ("override/extra", "{}", "topic", "unknown command"),
    ("override", "", "payload", "empty"),
    ("override", "hold 2h", "payload", "not JSON"),
    ("override", "[36]", "payload", "JSON object"),
    ("override", '{"command": "resume"}', "command", "the topic names the command"),
    ("override", '{"louver_deg": "36"}', "louver_deg", "finite number"),
    ("override", '{"louver_deg": 1e400}', "louver_deg", "finite number"),
    ("override", '{"louver_deg": 45}', "louver_deg", "nearest: 36 or 54"),
    ("override", '{"or_pct": 150}', "or_pct", "outside 0..100"),
    ("override", '{"hold": "9d"}', "hold", "between"),
    ("override", '{"speed": 3}', "speed", "unknown field"),
    ("override", "[" * 600 + "]" * 400, "payload", "not JSON"),
    ("regime", "7: all dampers open", "regime", "not a regime option"),
    ("regime", "11", "regime", "1..10"),
    ("regime", "seven", "regime", "expected a number"),
    ("louver_deg", "NaN", "louver_deg", "expected a number"),
    ("louver_deg", "true", "louver_deg", "expected a number"),
    ("louver_deg", "0x24", "louver_deg", "expected a number"),
    ("louver_deg", "9" * 500, "louver_deg", "finite number"),
    ("damper_pct", "42.5", "or_pct", "steps"),
    ("resume", "PRESS", "payload", "not JSON"),
    ("resume", '{"hold": "2h"}', "hold", "resume takes no other fields"),
    ("mode", "HEATING", "mode", "heating, cooling, auto"),
    ("mode", '{"mode": 1}', "mode", "heating, cooling, auto"),
])
def test_malformed_or_impossible_payloads_name_what_is_wrong(cfg, subtopic, payload, field,
                                                             words) -> None:
    with pytest.raises(CommandError) as err:
        validate_command(cfg, request_of(subtopic, payload.encode()))
    assert err.value.field == field and words in str(err.value)


def test_bytes_that_are_not_text_are_refused_and_shown_escaped() -> None:
    with pytest.raises(CommandError, match="not UTF-8"):
        request_of("override", b"\xff\xfe{}")
    assert shown(b"\xff{") == "\\xff{"
    long = shown(b"\xff" * 5000)
    assert long.startswith("\\xff") and long.endswith("… (5000 bytes)")
    assert len(long) <= SHOWN_BYTES + len("… (5000 bytes)")


def test_the_receiver_files_commands_as_the_cli_does_and_answers_the_rest(cfg,
                                                                          tmp_path: Path):
    store = Store.open(tmp_path)
    store.begin_run(panel=cfg.panel.id, mode="test", version="0", config_path=None)
    answers: list[dict] = []
    r = CommandReceiver(cfg, base_topic=BASE, broker="127.0.0.1:1883",
                        answer=lambda text: answers.append(json.loads(text)))

    def msg(sub: str, payload: bytes, *, retained: bool = False) -> _Message:
        return _Message(f"{BASE}/cmd/{sub}", payload[:MAX_PAYLOAD_BYTES + 1], len(payload),
                        retained)

    cid = r.handle(msg("override", b'{"hold": "30min", "regime": 3}'), database=store.path)
    assert r.handle(msg("resume", b"resume", retained=True), database=store.path) is None
    assert r.handle(msg("override", b'{"hold": "2h", "pad": "' + b"x" * 3000 + b'"}'),
                    database=store.path) is None
    assert r.handle(msg("regime", b"11"), database=store.path) is None
    rows = store.conn.execute("SELECT command_id, kind, args, source, requester, status "
                              "FROM commands").fetchall()
    assert rows == [(cid, "override", '{"hold":"30min","regime":3}', "mqtt",
                     f"127.0.0.1:1883 {BASE}/cmd/override", "pending")]
    assert [a["topic"] for a in answers] == [f"{BASE}/cmd/resume", f"{BASE}/cmd/override",
                                             f"{BASE}/cmd/regime"]
    assert "retained command" in answers[0]["reason"]
    assert answers[1]["payload_bytes"] == 3025 and "longer than 1024 bytes" in \
        answers[1]["reason"] and answers[1]["payload"].endswith("… (3025 bytes)")
    assert answers[2]["reason"] == "regime: 11: expected an airflow regime 1..10"
    assert (r.queued, r.refused) == (1, 3)
    store.close()


def test_a_flood_beyond_the_queue_is_dropped_counted_and_answered_once(cfg) -> None:
    from dsfd.integrations.mqtt.receiver import QUEUE_SIZE

    answers: list[dict] = []
    r = CommandReceiver(cfg, base_topic=BASE, broker="b:1883",
                        answer=lambda text: answers.append(json.loads(text)))
    for _ in range(QUEUE_SIZE + 44):  # paho's thread, while the receiver's is busy
        r.offer(f"{BASE}/cmd/resume", b"resume", False)
    assert r.queue.qsize() == QUEUE_SIZE and r.dropped == 44
    r._answer_drops()
    r._answer_drops()  # nothing new: no second answer
    assert [(a["topic"], a["reason"]) for a in answers] == [
        (f"{BASE}/cmd/#", f"44 command message(s) dropped unread: more than {QUEUE_SIZE} "
         "were waiting")]


def test_a_command_the_database_cannot_take_is_refused_and_answered(cfg, tmp_path: Path):
    answers: list[dict] = []
    r = CommandReceiver(cfg, base_topic=BASE, broker="b:1883",
                        answer=lambda text: answers.append(json.loads(text)))
    missing = tmp_path / "no-daemon-yet" / "timeseries.sqlite"  # opened read-write, never made
    msg = _Message(f"{BASE}/cmd/resume", b"resume", 6, False)
    assert r.handle(msg, database=missing) is None
    (answer,) = answers
    assert answer["topic"] == f"{BASE}/cmd/resume" and answer["payload"] == "resume"
    assert answer["reason"].startswith("not queued: the database cannot be written (")
    assert (r.queued, r.refused) == (0, 1) and not missing.exists()


def test_a_stored_request_whose_fields_are_not_json_is_rejected_naming_them(cfg,
                                                                           tmp_path: Path):
    from dsfd.storage.commands import pending

    store = Store.open(tmp_path)
    with store.conn:  # a row written by hand (sqlite3), not by dsfd
        store.conn.execute("INSERT INTO commands (requested_s, requested_utc, source, "
                           "requester, kind, args) VALUES (0, '', 'sql', 'me', 'override', "
                           "'hold=2h')")
    (row,) = pending(store.conn)
    assert row.args == {"args": "hold=2h"}
    with pytest.raises(CommandError) as exc:
        validate_command(cfg, row.request())
    assert exc.value.field == "args" and "unknown field for override" in str(exc.value)
    store.close()
