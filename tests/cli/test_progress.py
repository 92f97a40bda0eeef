"""Progress on stderr: redrawn on a terminal, plain lines every 10 % anywhere else."""

from __future__ import annotations

import io

from dsfd.cli.progress import Progress


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_log_gets_a_plain_line_every_ten_percent():
    log = io.StringIO()
    bar = Progress("replay", stream=log)
    for i in range(1, 1001):
        bar(i, 1000, f"{i // 100} updates")
    bar(1000, 1000)  # a repeated end adds nothing
    lines = log.getvalue().splitlines()
    assert "\r" not in log.getvalue()
    assert [line.split()[1] for line in lines] == [f"{p}%" for p in range(0, 101, 10)]
    assert lines[-1] == "replay: 100% (1000/1000) (10 updates)"


def test_a_terminal_gets_one_bar_redrawn_in_place():
    tty = Terminal()
    bar = Progress("fitting", stream=tty)
    for i in range(1, 51):
        bar(i, 50)
    text = tty.getvalue()
    assert text.count("\r") == 50 and text.count("\n") == 1 and text.endswith("\n")
    assert "[##############################] 100% 50/50" in text
