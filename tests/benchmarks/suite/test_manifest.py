"""The ``ogcp.suite-run/1`` manifest: built and read back by ogcp.benchmarks.suite.manifest."""

from __future__ import annotations

import json

from ogcp.benchmarks.suite.manifest import (
    MANIFEST_SCHEMA,
    ManifestSuite,
    first_commit,
    new_manifest,
    session_record,
    suite_hash,
    with_session,
)
from ogcp.benchmarks.suite.parse import parse_suite

SUITE = "schema_version = 1\nname = 'tiny'\nobjects = ['box']\ncontacts = 12\n[[methods]]\nmethod = 'astar'\n"


def test_a_manifest_reads_back_its_suite_and_sessions() -> None:
    suite = parse_suite(SUITE, source="tiny.toml")
    first = session_record(2, "loky", None, False, False, None, ("method=astar",), None)
    manifest = json.loads(json.dumps(new_manifest(suite, first)))
    assert manifest["schema"] == MANIFEST_SCHEMA and manifest["sessions"] == [first]
    assert first["only"] == ["method=astar"] and manifest["started_at"] == first["started_at"]
    read = ManifestSuite.of(manifest)
    assert read == ManifestSuite("tiny", "tiny.toml", suite.hash, len(suite.cells), False, SUITE)
    assert suite_hash(manifest) == suite.hash and first_commit(manifest) == first["git_commit"]
    second = {**first, "resume": True}
    resumed = with_session(manifest, second)
    assert resumed["sessions"] == [first, second] and manifest["sessions"] == [first]
    assert first_commit(resumed) == first["git_commit"]


def test_partial_manifests_read_as_unknown() -> None:
    assert ManifestSuite.of(None) is None and ManifestSuite.of({"suite": "x"}) is None and suite_hash({}) is None
    assert ManifestSuite.of({"suite": {"cells": True, "hash": 3}}) == ManifestSuite(None, None, None, None, None, None)
    assert first_commit({}) is None and first_commit({"sessions": []}) is None
    assert with_session({}, {"a": 1}) == {"sessions": [{"a": 1}]}
