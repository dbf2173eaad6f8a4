"""Study scripts run from a checkout (``python -m benchmarks.studies.NAME``); not part of the wheel."""
