"""Fetched hands: a hand's folder from a wheel, verified on fetch and on every load (no network: a local wheel)."""

from __future__ import annotations

import dataclasses
import shutil
import zipfile
from pathlib import Path

import pytest

from ogcp.benchmarks.cli import main as cli_main
from ogcp.planner.hands import HandKinematics, fetch, load_descriptor, resolve_hand
from ogcp.planner.infra.assets import asset_path
from ogcp.planner.infra.errors import OgcpError
from tests.planner.hands.hand_files import write_mesh_hand

FOLDER = "claw_pkg/models/claw"
LICENSE = "claw_pkg-1.0.dist-info/licenses/LICENSE"


@pytest.fixture()
def fake_wheel(tmp_path, monkeypatch):
    """A wheel holding the test's mesh hand, registered as the fetchable hand ``claw``; pip is replaced."""
    source = tmp_path / "source"
    write_mesh_hand(source)
    (source / "claw.toml").unlink()  # the descriptor ships with ogcp, not in the wheel
    wheel = tmp_path / "claw_pkg-1.0-py3-none-any.whl"
    files = {path.relative_to(source).as_posix(): path.read_bytes() for path in source.rglob("*") if path.is_file()}
    with zipfile.ZipFile(wheel, "w") as archive:
        for relative, data in files.items():
            archive.writestr(f"{FOLDER}/{relative}", data)
        archive.writestr(LICENSE, b"Apache License 2.0 (test)\n")
        archive.writestr("claw_pkg/__init__.py", b"")
    stored = {**files, "LICENSE": b"Apache License 2.0 (test)\n"}
    entry = fetch.FetchableHand(
        name="claw",
        package="claw-pkg",
        version="1.0",
        license="Apache-2.0",
        wheel=wheel.name,
        wheel_sha256="0" * 64,
        folder=FOLDER,
        license_member=LICENSE,
        tree_sha256=fetch.tree_digest(stored),
        files=len(stored),
        description="a test hand",
    )
    monkeypatch.setitem(fetch.FETCHABLE_HANDS, "claw", entry)
    downloads: list[str] = []

    def download(requirement, name, dest, progress=False):
        downloads.append(requirement)
        return Path(shutil.copy(wheel, dest / name))

    monkeypatch.setattr(fetch.wheels, "download_wheel", download)
    return downloads


@pytest.fixture()
def cache(tmp_path, monkeypatch):
    root = tmp_path / "cache"
    monkeypatch.setenv("OGCP_CACHE", str(root))
    return root


def _descriptor(tmp_path: Path) -> Path:
    source = tmp_path / "describe"
    write_mesh_hand(source)
    text = (source / "claw.toml").read_text().replace('mjcf = "claw.xml"', 'fetched = "claw"\nmjcf = "claw.xml"')
    path = tmp_path / "claw_fetched.toml"
    path.write_text(text)
    return path


def test_fetch_extracts_verifies_and_keeps_the_licence(cache, fake_wheel, tmp_path):
    lines: list[str] = []
    done = fetch.fetch_hands(["claw"], log=lines.append)
    folder = cache / "hands" / "claw"
    assert done == {"claw": folder} and fake_wheel == ["claw-pkg==1.0"]
    assert (folder / "LICENSE").read_bytes().startswith(b"Apache") and (folder / "meshes" / "link.stl").is_file()
    assert fetch.fetched_folder("claw") == folder
    descriptor = load_descriptor(_descriptor(tmp_path))
    assert descriptor.model_path == folder / "claw.xml"
    assert HandKinematics(descriptor).joint_names == ("f0_a", "f0_b", "f1_a", "f1_b", "f2_a", "f2_b")
    assert "digest verified" in lines[-1] and "Apache-2.0" in lines[-1]
    assert not [p for p in (cache / "hands").iterdir() if p.name.startswith(".")]  # no staging left


def test_a_cached_hand_is_skipped_unless_forced(cache, fake_wheel):
    fetch.fetch_hands(["claw"], log=lambda line: None)
    lines: list[str] = []
    assert fetch.fetch_hands(["claw"], log=lines.append) == {} and len(fake_wheel) == 1
    assert "already cached" in lines[-1]
    assert set(fetch.fetch_hands(["claw"], force=True, log=lambda line: None)) == {"claw"} and len(fake_wheel) == 2


def test_a_damaged_folder_is_named_on_load_and_fetched_again(cache, fake_wheel, tmp_path):
    fetch.fetch_hands(["claw"], log=lambda line: None)
    mesh = cache / "hands" / "claw" / "meshes" / "tip.stl"
    mesh.write_bytes(mesh.read_bytes()[:-10])
    with pytest.raises(OgcpError) as info:
        load_descriptor(_descriptor(tmp_path))
    message = str(info.value)
    assert "does not match the registered files of claw-pkg==1.0" in message and "\n" not in message
    assert "`ogcp assets fetch claw --force`" in message
    lines: list[str] = []
    assert set(fetch.fetch_hands(["claw"], log=lines.append)) == {"claw"}  # repaired without --force
    assert "fetching it again" in lines[0] and fetch.fetched_folder("claw")


def test_a_hand_not_fetched_names_the_command(cache, fake_wheel, tmp_path):
    with pytest.raises(OgcpError, match=r"hand 'claw' is not in the cache .*`ogcp assets fetch claw`$"):
        load_descriptor(_descriptor(tmp_path))
    with pytest.raises(OgcpError, match="shadow_hand.*ogcp assets fetch shadow_hand"):
        resolve_hand("shadow_hand")


def test_a_digest_mismatch_caches_nothing(cache, fake_wheel, monkeypatch):
    entry = dataclasses.replace(fetch.FETCHABLE_HANDS["claw"], tree_sha256="1" * 64)
    monkeypatch.setitem(fetch.FETCHABLE_HANDS, "claw", entry)
    with pytest.raises(OgcpError, match="nothing was cached"):
        fetch.fetch_hands(["claw"], log=lambda line: None)
    assert not (cache / "hands").exists() or not list((cache / "hands").iterdir())


def test_unknown_hand_lists_the_fetchable_ones(cache):
    with pytest.raises(OgcpError, match="unknown fetchable hand 'nope'; valid choices: shadow_hand"):
        fetch.fetch_hands(["nope"])


def test_cli_fetches_hands_and_lists_them(cache, fake_wheel, capsys):
    assert cli_main(["assets", "fetch", "claw", "box"]) == 0
    assert fetch.is_cached("claw") and "hands fetched 1" in capsys.readouterr().err
    assert cli_main(["assets", "list"]) == 0
    rows = {line.split()[0]: line for line in capsys.readouterr().out.splitlines() if line.strip()}
    assert "fetchable" in rows["claw"] and " yes " in rows["claw"] and " no " in rows["shadow_hand"]
    assert "builtin" in rows["sdh"]
    assert cli_main(["assets", "fetch", "nope"]) == 2
    assert "unknown object or hand 'nope'" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda t: t.replace('tree_sha256 = "', 'tree_sha256 = "x'), "tree_sha256: expected 64 lower-case hex"),
        (lambda t: t.replace("files = 21", "files = 1"), "files: expected a count of at least 2"),
        (lambda t: t.replace('folder = "', 'folder = "../'), "folder: expected a relative path inside the wheel"),
        (lambda t: t.replace('license = "Apache-2.0"\n', ""), "missing key 'license'"),
        (lambda t: t + "colour = 1\n", "unknown key 'colour'"),
        (lambda t: t.replace("schema_version = 1", "schema_version = 2"), "schema_version: expected 1"),
    ],
)
def test_manifest_errors_are_one_line(edit, message):
    text = asset_path(fetch.MANIFEST).read_text()
    assert fetch.parse_manifest(text)["shadow_hand"].files == 21
    with pytest.raises(OgcpError, match=message) as info:
        fetch.parse_manifest(edit(text))
    assert "\n" not in str(info.value)
