"""Sampled contact sets kept on disk, so that asking again skips the mesh library.

Sampling a built-in object or a mesh file needs trimesh, whose import alone costs more
than planning on a small set (about 0.45 s here). A request names everything that decides
its contact set: the object (built-in name, or mesh file path and the sha256 of its
bytes), the diagonal, n, the seed, mu, the cone edges, the tip radius and the torsional
friction. The entry's key adds the versions of numpy, scipy and trimesh and a digest of
ogcp's own sampling code, so an upgrade or an edit of that code never returns a stale set.
Entries are sealed and checked on load by :mod:`ogcp.planner.infra.cache`; a damaged one is
discarded and sampled again, and a cache folder that cannot be written costs only the time.

Fetched objects (``ogcp assets fetch``) are not cached here: they are meshes in the cache already.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from importlib import metadata
from pathlib import Path
from typing import Any

from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.infra.cache import cache_dir, file_sha256, read_entry, write_entry
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.objects.builtin import BUILTIN_OBJECTS

#: Cache subfolder of the entries.
SUBDIR = "contacts"
#: Packages whose code decides a sampled set (contacts, reach, wrenches; objects and scaling).
_SAMPLING_PACKAGES = ("grasp", "objects")
_LIBRARIES = ("numpy", "scipy", "trimesh")


@dataclass(frozen=True)
class ContactRequest:
    """Everything that decides a sampled contact set.

    Attributes:
        spec: Built-in object name or mesh file path, as given.
        diagonal: Bounding-box diagonal [m]; None for the object's default.
        n: Number of contacts.
        seed: Sampling seed.
        mu: Friction coefficient [-].
        cone_edges: Friction cone edges.
        tip_radius: Fingertip radius [m]; None for the default fingertip of the object.
        torsional_friction: Torsional friction coefficient [m] (0: hard contacts).
    """

    spec: str
    diagonal: float | None
    n: int
    seed: int
    mu: float
    cone_edges: int
    tip_radius: float | None
    torsional_friction: float


@lru_cache(maxsize=1)
def _code_digest() -> str:
    """sha256 over ogcp's sampling code and the versions of the libraries it calls."""
    digest = hashlib.sha256()
    root = Path(__file__).resolve().parents[1]
    for package in _SAMPLING_PACKAGES:
        for path in sorted((root / package).rglob("*.py")):
            digest.update(path.relative_to(root).as_posix().encode())
            digest.update(path.read_bytes())
    for name in _LIBRARIES:
        try:
            digest.update(f"{name}={metadata.version(name)}".encode())
        except metadata.PackageNotFoundError:
            digest.update(f"{name}=?".encode())
    return digest.hexdigest()


def request_key(request: ContactRequest) -> dict[str, Any] | None:
    """The JSON key of a request, or None when it is not cached (fetched objects, missing files)."""
    key: dict[str, Any] = {"request": request.__dict__.copy(), "code": _code_digest()}
    if request.spec in BUILTIN_OBJECTS:
        key["object"] = "builtin"
        return key
    path = Path(request.spec)
    if not path.is_file():
        return None  # a fetched name, or an error resolve_object reports
    try:
        key["object"] = file_sha256(path)
    except OSError:
        return None
    return key


def _folder(key: dict[str, Any]) -> Path:
    text = json.dumps(key, sort_keys=True)
    return cache_dir(SUBDIR) / hashlib.sha256(text.encode()).hexdigest()[:32]


def _load(expected: dict[str, Any], n: int) -> Callable[[Path], ContactSet]:
    def load(folder: Path) -> ContactSet:
        if json.loads((folder / "key.json").read_text()) != expected:
            raise ValueError("key.json does not match the request (a hash collision or an edited entry)")
        # An invalid field raises OgcpError, a ValueError: read_entry discards the entry.
        contacts = ContactSet.from_dict(json.loads((folder / "contacts.json").read_text()), str(folder))
        if len(contacts) != n:
            raise ValueError(f"{len(contacts)} contacts stored for a request of {n}")
        return contacts

    return load


def cached_contacts(request: ContactRequest, sample: Callable[[], ContactSet]) -> ContactSet:
    """The contact set of a request: from the cache when an entry verifies, else sampled and stored.

    Args:
        request: What decides the set.
        sample: Samples it (resolving the object with trimesh); called on a miss only.

    Returns:
        The contact set, equal field for field to what ``sample`` returns for this request.
    """
    key = request_key(request)
    if key is None:
        return sample()
    folder = _folder(key)
    try:
        found = read_entry(folder, _load(key, request.n))
    except OgcpError:
        found = None  # an unreadable cache folder: sample instead
    if found is not None:
        return found
    contacts = sample()

    def build(stage: Path) -> None:
        (stage / "key.json").write_text(json.dumps(key, sort_keys=True))
        (stage / "contacts.json").write_text(json.dumps(contacts.to_dict()))

    try:
        write_entry(folder, build)
    except OgcpError:
        pass  # a read-only or full cache costs the next run its sampling time, nothing else
    return contacts
