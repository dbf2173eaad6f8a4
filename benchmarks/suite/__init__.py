"""Benchmark suites: TOML definitions expanded into cells, the resumable runner and its results store."""
