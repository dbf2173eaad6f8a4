"""numba's on-disk cache of the compiled kernels, with every file checked before it is loaded.

numba caches compiled code (``cache=True``) as pickles: an index ``<function>.nbi`` and one
``<function>.<i>.nbc`` per signature, in ``__pycache__`` beside the source or under
``NUMBA_CACHE_DIR``. It checks neither: a truncated or overwritten file makes the first call
of the kernel raise (``UnpicklingError``, ``EOFError``, ``UnicodeDecodeError``) in every run
until the file is deleted by hand, and bytes changed inside the machine code may load and run.

:func:`cached_njit` is ``numba.njit(cache=True)`` with sealed files: each is written (atomically,
as numba writes) as one header line ``ogcp.numba-cache/1 <numba version> <sha256 of the rest>``
and numba's pickle, under names of its own (``<function>.ogcp.nbi``), so numba's plain files
are never read. A file that fails its check is reported in one line
(:class:`~ogcp.planner.infra.cache.CacheEntryWarning`), removed and read as absent: numba compiles
the kernel again and writes it back. A damaged cache costs one compilation, never a failed
run. A file of another numba version is stale, not damaged: it is overwritten silently.

Where the local cache has no entry for a signature, the kernels that ship with ogcp are looked
up (:mod:`.shipped`: compiled for the x86-64-v3 level, keyed by the sources' content), so a
fresh install does not compile.

This leans on numba's cache classes (``FunctionCache``, ``IndexDataCacheFile``), which have
kept their shape since numba 0.49; the tests of this module damage real cache files.
"""

from __future__ import annotations

import hashlib
import pickle
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numba
from numba import njit
from numba.core.caching import FunctionCache, IndexDataCacheFile

from ogcp.planner.grasp.kernel import shipped
from ogcp.planner.infra.cache import CacheEntryWarning

__all__ = ["HEADER", "cached_njit", "restamp_index"]

HEADER = "ogcp.numba-cache/1"
#: The header line is short; a file without a newline this early is not one of ours.
_MAX_HEADER = 256


def cached_njit(**options: Any) -> Callable[[Callable[..., Any]], Any]:
    """``numba.njit(cache=True, **options)`` whose cache files are sealed and checked on load."""

    def decorate(func: Callable[..., Any]) -> Any:
        dispatcher = njit(cache=False, **options)(func)
        try:
            # What Dispatcher.enable_caching does, with the checked cache in place of numba's own.
            dispatcher._cache = _SealedFunctionCache(func)
        except (AttributeError, TypeError):  # pragma: no cover - another numba's cache classes
            return njit(cache=True, **options)(func)
        return dispatcher

    return decorate


class _SealedFunctionCache(FunctionCache):
    """numba's per-function cache, reading and writing :class:`_SealedCacheFile` files."""

    def __init__(self, py_func: Callable[..., Any]) -> None:
        super().__init__(py_func)
        self._cache_file = _SealedCacheFile(
            cache_path=self._cache_path,
            filename_base=f"{self._impl.filename_base}.ogcp",
            source_stamp=self._impl.locator.get_source_stamp(),
        )
        self._shipped: _ShippedCacheFile | None = None
        if shipped.enabled() and shipped.shipped_index(self._impl.filename_base).is_file():
            self._shipped = _ShippedCacheFile(
                cache_path=str(shipped.SHIPPED),
                filename_base=f"{self._impl.filename_base}.ogcp",
                source_stamp=shipped.shipped_stamp(),
            )

    @property
    def ships(self) -> bool:
        """Whether this kernel has a shipped cache for the current sources (it may still lack a signature)."""
        return self._shipped is not None and bool(self._shipped.overloads())

    def _load_overload(self, sig: Any, target_context: Any) -> Any:
        data = super()._load_overload(sig, target_context)
        if data is None and self._shipped is not None:
            found = self._shipped.load(shipped.shipped_key(self._index_key(sig, target_context.codegen())))
            if found is not None:
                data = self._impl.rebuild(target_context, found)
        return data


class _SealedCacheFile(IndexDataCacheFile):
    """numba's index and data files, each behind a header line with its sha256."""

    def _save_index(self, overloads: dict[Any, str]) -> None:
        self._write(self._index_path, (self._source_stamp, overloads))

    def _load_index(self) -> dict[Any, str]:
        content = self._read(self._index_path)
        if content is None:
            return {}
        if not (isinstance(content, tuple) and len(content) == 2 and isinstance(content[1], dict)):
            self._discard(self._index_path, "not an index")
            return {}
        stamp, overloads = content
        # Another source file (edited since): stale, overwritten by the next save as numba does.
        return overloads if stamp == self._source_stamp else {}

    def _save_data(self, name: str, data: Any) -> None:
        self._write(self._data_path(name), data)

    def _load_data(self, name: str) -> Any:
        # None reads as a miss: numba compiles the kernel and saves it under the same name.
        return self._read(self._data_path(name))

    def _write(self, path: str, obj: Any) -> None:
        body = self._dump(obj)
        header = f"{HEADER} {numba.__version__} {hashlib.sha256(body).hexdigest()}\n".encode()
        with self._open_for_write(path) as handle:  # a temporary file renamed into place
            handle.write(header + body)

    def _read(self, path: str) -> Any:
        """The object a sealed file holds; None when absent, stale or damaged (reported, removed)."""
        try:
            blob = Path(path).read_bytes()
        except FileNotFoundError:
            return None
        except OSError as exc:
            warnings.warn(
                f"numba cache file {path} is unreadable ({exc.strerror or exc}); compiling", CacheEntryWarning, 2
            )
            return None
        end = blob.find(b"\n", 0, _MAX_HEADER)
        fields = blob[:end].split(b" ") if end > 0 else []
        if len(fields) != 3 or fields[0] != HEADER.encode():
            return self._discard(path, "no ogcp header")
        if fields[1] != numba.__version__.encode():
            return None  # written by another numba: stale, overwritten by the next save
        body = blob[end + 1 :]
        if hashlib.sha256(body).hexdigest().encode() != fields[2]:
            return self._discard(path, f"its sha256 differs from its header, {len(body)} bytes")
        try:
            return pickle.loads(body)
        except Exception as exc:  # noqa: BLE001 - unpickling runs numba's constructors: any error is damage
            return self._discard(path, f"{type(exc).__name__} on unpickling")

    @staticmethod
    def _discard(path: str, reason: str) -> None:
        warnings.warn(
            f"numba cache file {path} is damaged ({reason}); discarded, the kernel is compiled again",
            CacheEntryWarning,
            3,
        )
        try:
            Path(path).unlink(missing_ok=True)
        except OSError:
            pass  # not ours to remove: the next save replaces it, or the next run reports it again


class _ShippedCacheFile(_SealedCacheFile):
    """A shipped kernel's files (:mod:`.shipped`): read only, the index read once."""

    _index: dict[Any, str] | None = None

    def overloads(self) -> dict[Any, str]:
        """The index's entries; empty when it is stale (other sources) or damaged."""
        if self._index is None:
            self._index = super()._load_index()
        return self._index

    def _load_index(self) -> dict[Any, str]:
        return self.overloads()

    def _save_index(self, overloads: dict[Any, str]) -> None:
        raise RuntimeError("shipped kernels are read only")

    def _save_data(self, name: str, data: Any) -> None:
        raise RuntimeError("shipped kernels are read only")

    @staticmethod
    def _discard(path: str, reason: str) -> None:
        # Part of the installation: reported and skipped (the kernel compiles), never removed.
        warnings.warn(
            f"shipped kernel file {path} is damaged ({reason}); skipped, the kernel is compiled", CacheEntryWarning, 3
        )


def restamp_index(source: str | Path, target: str | Path, stamp: tuple[str, str]) -> None:
    """Copy a sealed index from ``source`` to ``target`` with its source stamp replaced by ``stamp``.

    Raises:
        ValueError: When ``source`` is not a readable sealed index.
    """
    reader = _SealedCacheFile(cache_path=str(Path(source).parent), filename_base="unused", source_stamp=None)
    content = reader._read(str(source))
    if not (isinstance(content, tuple) and len(content) == 2 and isinstance(content[1], dict)):
        raise ValueError(f"{source} is not a sealed numba cache index")
    writer = _SealedCacheFile(cache_path=str(Path(target).parent), filename_base="unused", source_stamp=stamp)
    writer._write(str(target), (stamp, content[1]))
