"""Study scripts run from a checkout (``python -m ogcp.benchmarks.studies.NAME``); not part of the wheel."""
