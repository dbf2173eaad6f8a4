"""pytest-benchmark speed benchmarks (see README: run with --benchmark-enable)."""
