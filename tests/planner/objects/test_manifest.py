"""The manifest of fetchable objects, assets/objects.toml: what it holds and how it is validated."""

from __future__ import annotations

import re
import tomllib

import pytest

from ogcp.planner.infra import OgcpError, asset_path
from ogcp.planner.objects.fetchable import FETCHABLE_OBJECTS, PAPER_OBJECTS, parse_manifest

SHIPPED = asset_path("objects.toml").read_text()


def _edited(edit: str, replacement: str) -> str:
    """The shipped manifest with its first match of regex ``edit`` replaced."""
    text, count = re.subn(edit, replacement, SHIPPED, count=1, flags=re.MULTILINE)
    assert count == 1, edit
    return text


def test_shipped_manifest_is_the_registry():
    manifest = parse_manifest(SHIPPED)
    assert manifest.objects == FETCHABLE_OBJECTS
    assert manifest.paper_objects == PAPER_OBJECTS
    assert list(FETCHABLE_OBJECTS) == list(tomllib.loads(SHIPPED)["objects"])


def test_objects_sharing_a_wheel_agree_on_it():
    by_wheel: dict[str, set[tuple[str, str, str]]] = {}
    for entry in FETCHABLE_OBJECTS.values():
        by_wheel.setdefault(entry.wheel, set()).add((entry.package, entry.version, entry.wheel_sha256))
    assert all(len(variants) == 1 for variants in by_wheel.values())


@pytest.mark.parametrize(
    ("edit", "replacement", "message"),
    [
        (r"^schema_version = 1", "schema_version = 2", "schema_version: expected 1, got 2"),
        (r"^paper_objects = .*$", "", "missing key 'paper_objects'"),
        (r"^paper_objects = .*$", "paper_objects = ['box', 'box']", "paper_objects: names must not repeat"),
        (r"^paper_objects = .*$", "paper_objects = 'box'", "paper_objects: expected a list of object names"),
        (r'^sha256 = "37.*$', "", "objects.bunny: missing key 'sha256'"),
        (r"^vertices = 28088", "vertices = 28088\ncolour = 'red'", "objects.bunny: unknown key 'colour'"),
        (r'^sha256 = "37.*$', 'sha256 = "37ab"', "objects.bunny.sha256: expected 64 lower-case hex digits"),
        (r'^wheel_sha256 = "c3.*$', 'wheel_sha256 = "C3"', "objects.bunny.wheel_sha256: expected 64"),
        (r"^vertices = 28088", "vertices = true", "objects.bunny.vertices: expected int, got True"),
        (r"^vertices = 28088", "vertices = 0", "objects.bunny.vertices: expected a positive count"),
        (r"^watertight = true", "watertight = 'yes'", "objects.bunny.watertight: expected bool"),
        (r'^license = "GPL.*$', 'license = " "', "objects.bunny.license: must not be empty"),
        (r'^member = "pymeshlab/tests.*$', 'member = "/etc/passwd"', "objects.bunny.member: expected a relative path"),
        (r'^member = "pymeshlab/tests.*$', 'member = "../x.obj"', "objects.bunny.member: expected a relative path"),
        (r'^wheel = "pymeshlab.*$', 'wheel = "pymeshlab.zip"', "objects.bunny.wheel: not a wheel file name"),
        (r'^version = "2025.*$', 'version = "2024.1"', "objects.bunny.wheel: .* is not a wheel of pymeshlab==2024.1"),
        (r"^\[objects.bunny\]", "[objects.Bunny]", "objects.Bunny: object names are lower-case"),
        (r"^\[objects.bunny\]", "[objects.bunny]]", "invalid TOML"),
    ],
)
def test_invalid_manifest_names_the_file_and_key(edit, replacement, message):
    with pytest.raises(OgcpError, match=f"^objects.toml: .*{message}"):
        parse_manifest(_edited(edit, replacement), source="objects.toml")
