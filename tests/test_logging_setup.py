"""The launch's console log follows sys.stderr: a record emitted after the stream it started on
was swapped and closed (an in-process launch under a test runner or a notebook) still lands."""

from __future__ import annotations

import io
import logging
import sys

from twil_control.launch.logging_setup import configure_logging


def test_records_go_to_the_current_stderr_after_the_first_one_is_closed(monkeypatch):
    root = logging.getLogger()
    saved = (root.handlers[:], root.level)
    try:
        first = io.StringIO()
        monkeypatch.setattr(sys, "stderr", first)
        configure_logging()
        logging.getLogger("twil_control.node.amcl").info("first")
        first.close()
        second = io.StringIO()
        monkeypatch.setattr(sys, "stderr", second)
        logging.getLogger("twil_control.node.amcl").warning("second")
        assert second.getvalue() == "[WARNING] [-]: /amcl: second\n"
    finally:
        root.handlers[:], root.level = saved
