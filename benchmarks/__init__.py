"""ogcp's user-facing layer: the ``ogcp`` command line, suites, regression checks and plots."""
