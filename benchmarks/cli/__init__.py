"""The ``ogcp`` command line: one module per command group, all thin over the Python API."""

from ogcp.benchmarks.cli.app import build_parser, main

__all__ = ["build_parser", "main"]
