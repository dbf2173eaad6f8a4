"""An exception ogcp did not expect (a bug) still ends the command in one line, and can show where."""

from __future__ import annotations

import argparse

import pytest

from ogcp.benchmarks.cli import app
from tests.cli_run import run_cli


class _BrokenParser:
    def parse_args(self, argv: object) -> argparse.Namespace:
        def handler(args: argparse.Namespace) -> int:
            raise NameError("name 'cKDTree' is not defined\nmore the user need not read")

        return argparse.Namespace(handler=handler)


def test_a_bug_is_one_line_naming_the_exception(monkeypatch):
    monkeypatch.delenv(app.TRACEBACK_VARIABLE, raising=False)
    monkeypatch.setattr(app, "build_parser", _BrokenParser)
    status, out, err = run_cli(["plan", "box"])
    assert status == 2 and out == ""
    assert err == (
        "ogcp: error: internal error (NameError: name 'cKDTree' is not defined), a bug in ogcp: please report it "
        "with the command; OGCP_TRACEBACK=1 shows where\n"
    )


def test_the_traceback_variable_lets_the_exception_through(monkeypatch):
    monkeypatch.setenv(app.TRACEBACK_VARIABLE, "1")
    monkeypatch.setattr(app, "build_parser", _BrokenParser)
    with pytest.raises(NameError, match="cKDTree"):
        run_cli(["plan", "box"])
