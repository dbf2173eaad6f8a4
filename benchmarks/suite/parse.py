"""Reading suites: built-in names and TOML files, validated into a :class:`~ogcp.benchmarks.suite.config.Suite`.

Every problem is reported as one ``OgcpError`` naming the suite, the key path and the valid
values; nothing is run until the whole file is valid.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import re
import string
import tomllib
from pathlib import Path
from typing import Any

from ogcp.benchmarks.suite.config import (
    EXTERNAL_METHOD,
    GROUP_KEYS,
    SCHEMA_VERSION,
    SUITES_FOLDER,
    TOP_KEYS,
    Cell,
    ObjectSpec,
    Suite,
    best_grasp,
)
from ogcp.benchmarks.suite.params import (
    METHOD_PARAMS,
    UNLABELLED,
    complete,
    contact_models,
    default_label,
    seed_values,
    values_of,
)
from ogcp.planner.config.methods import DEFAULT_FINGERS, DEFAULT_SEED
from ogcp.planner.config.options import Option
from ogcp.planner.grasp.defaults import (
    CONE_EDGES,
    DEFAULT_CONE_EDGES,
    DEFAULT_CONTACTS,
    DEFAULT_MU,
    DIAGONAL,
    MU,
    TIP_RADIUS,
    check_contact_memory,
)
from ogcp.planner.grasp.wrench import primitives_per_contact
from ogcp.planner.hands.registry import is_descriptor_path, resolve_hand
from ogcp.planner.infra.assets import asset_path, assets_dir
from ogcp.planner.infra.errors import OgcpError, choice_error
from ogcp.planner.objects import BUILTIN_OBJECTS, DEFAULT_DIAGONAL, MESH_SUFFIXES, file_sha256
from ogcp.planner.objects.fetchable import FETCHABLE_OBJECTS
from ogcp.planner.records.grasps import ExternalGrasps, is_object_name, load_grasps

#: Most cells of one suite. Every cell is a planning run of a second or more and a line of
#: results; a million cells took more than 20 s to list before the first one ran. Split larger
#: studies into several suites.
MAX_CELLS = 100_000
#: Longest label: a plot legend or a table column, not a text (and a format width of 10^12
#: asked for terabytes).
MAX_LABEL = 200
#: Keys of an external method table (``method = "external"``).
EXTERNAL_KEYS = ("grasps", "label", "method")
#: Contact counts and m of a suite: a grasp has m >= 2 contacts, so a set has at least 2.
CONTACT_COUNT = Option("int", DEFAULT_CONTACTS, minimum=2)
FINGERS = Option("int", DEFAULT_FINGERS, minimum=2)


def builtin_suites() -> list[str]:
    """Names of the suites shipped in ``assets/suites``."""
    return sorted(p.stem for p in (assets_dir() / SUITES_FOLDER).glob("*.toml"))


def load_suite(spec: str | Path) -> Suite:
    """Read and validate a suite from a built-in name or a TOML file.

    Raises:
        OgcpError: For a missing file, invalid TOML or any invalid entry.
    """
    path = Path(spec)
    if not path.is_file():
        if str(spec) not in builtin_suites():
            raise choice_error("suite", str(spec), [*builtin_suites(), "<path to a suite .toml file>"])
        path = asset_path(f"{SUITES_FOLDER}/{spec}.toml")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise OgcpError(f"cannot read suite {path}: {exc}") from exc
    return parse_suite(text, source=str(spec), base=path.resolve().parent, default_name=path.stem)


def parse_suite(text: str, source: str = "<string>", base: Path | None = None, default_name: str = "suite") -> Suite:
    """Validate suite TOML text.

    Args:
        text: TOML content.
        source: Where the text came from, for messages and the manifest.
        base: Folder that relative mesh paths are relative to (default: the working directory).
        default_name: Name when the suite sets none.

    Raises:
        OgcpError: ``suite SOURCE: KEY: problem; valid ...`` for the first problem found.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise OgcpError(f"suite {source}: invalid TOML: {exc}") from exc
    try:
        return _Parser(base or Path.cwd()).suite(data, source, text, default_name)
    except OgcpError as exc:
        raise OgcpError(f"suite {source}: {exc}") from exc


class _Parser:
    """Validation of parsed TOML; every method raises OgcpError naming the key path."""

    def __init__(self, base: Path) -> None:
        self.base = base
        self.default_tip: float | None = None
        #: label -> (key path, method, parameters) of the variant it names first.
        self.labels: dict[str, tuple[str, str, dict[str, Any]]] = {}
        #: Cells of the groups read so far (a cell two groups list counts twice).
        self.cell_count = 0
        #: sha256 of each external grasps file read so far -> its absolute path and record.
        self.external: dict[str, tuple[str, ExternalGrasps]] = {}

    def suite(self, data: dict[str, Any], source: str, text: str, default_name: str) -> Suite:
        _no_unknown_keys("top level", data, TOP_KEYS)
        if "schema_version" not in data:
            raise OgcpError("schema_version: missing; valid values: 1")
        if data["schema_version"] != SCHEMA_VERSION or isinstance(data["schema_version"], bool):
            raise OgcpError(f"schema_version: unsupported value {data['schema_version']!r}; valid values: 1")
        name = _string("name", data.get("name", default_name))
        _string("description", data.get("description", ""))
        defaults = {k: v for k, v in data.items() if k in GROUP_KEYS and k not in ("name", "description")}
        groups = data.get("group")
        if groups is None:
            tables = [("top level", {"name": name, **defaults})]
        elif not isinstance(groups, list) or not groups or not all(isinstance(g, dict) for g in groups):
            raise OgcpError("group: expected one or more [[group]] tables")
        else:
            tables = [(f"group[{i}]", {**defaults, **g}) for i, g in enumerate(groups)]
        simulation = self.simulation(data.get("simulation", {}))
        # The [simulation] table's fingertip is the one the contacts are kept for by default.
        self.default_tip = simulation.get("tip_radius")
        if self.default_tip is not None:
            self.default_tip = TIP_RADIUS.check("simulation.tip_radius", self.default_tip)
            if self.default_tip == 0:
                raise OgcpError("simulation.tip_radius: expected a number > 0 [m] (or leave it unset), got 0")
        cells: dict[str, Cell] = {}
        names: set[str] = set()
        for where, table in tables:
            _no_unknown_keys(where, table, GROUP_KEYS)
            group = _string(f"{where}.name", table.get("name", where))
            if group in names:
                raise OgcpError(f"{where}.name: group name {group!r} is used twice")
            names.add(group)
            for cell in self.group_cells(where, group, table):
                _merge(cells, cell)
        return Suite(name, source, text, tuple(cells.values()), simulation)

    def group_cells(self, where: str, group: str, table: dict[str, Any]) -> list[Cell]:
        for key in ("objects", "methods"):
            if key not in table:
                raise OgcpError(f"{where}: missing key {key!r} (set it in the group or at the top level)")
        objects = self.objects(f"{where}.objects", table["objects"])
        contacts = values_of(f"{where}.contacts", table.get("contacts", DEFAULT_CONTACTS), CONTACT_COUNT)
        seeds = seed_values(f"{where}.contact_seeds", table.get("contact_seeds", DEFAULT_SEED))
        ms = values_of(f"{where}.m", table.get("m", DEFAULT_FINGERS), FINGERS)
        mus = values_of(f"{where}.mu", table.get("mu", DEFAULT_MU), MU)
        torsions = contact_models(where, table)
        edges = CONE_EDGES.check(f"{where}.cone_edges", table.get("cone_edges", DEFAULT_CONE_EDGES))
        simulate = Option("bool", True).check(f"{where}.simulate", table.get("simulate", True))
        diagonal = DIAGONAL.check(f"{where}.diagonal", table.get("diagonal", DEFAULT_DIAGONAL))
        # Mesh files keep their own size (diagonal None, so their cell ids are unchanged) unless
        # the suite gives a diagonal, which then scales them as it does named objects.
        mesh_diagonal = diagonal if "diagonal" in table else None
        # Absent: None, the default fingertip of each object (resolved when sampling).
        tips: list[float | None] = (
            values_of(f"{where}.tip_radius", table["tip_radius"], TIP_RADIUS)
            if "tip_radius" in table
            else [self.default_tip]
        )
        every = self.methods(f"{where}.methods", table["methods"])
        # External grasps bring their own contacts, m and mu: one cell per file, outside the product.
        variants = [v for v in every if v[0] != EXTERNAL_METHOD]
        external = [self.external_cell(where, group, objects, simulate, v) for v in every if v[0] == EXTERNAL_METHOD]
        if max(ms) > min(contacts):
            raise OgcpError(f"{where}.m: m = {max(ms)} exceeds the contact count {min(contacts)}")
        count = math.prod(map(len, (objects, contacts, seeds, ms, mus, torsions, tips, variants))) + len(external)
        self.cell_count += count
        if self.cell_count > MAX_CELLS:  # counted before the cells are made
            raise OgcpError(
                f"{where}: {count} cells ({len(objects)} objects x {len(contacts)} contact counts x {len(seeds)} "
                f"seeds x {len(ms)} m x {len(mus)} mu x {len(torsions)} contact models x {len(tips)} tip radii x "
                f"{len(variants)} method variants"
                f" + {len(external)} external grasps files), "
                f"{self.cell_count} with the groups before; at most {MAX_CELLS} per suite: split it into several suites"
            )
        try:
            # Before any cell runs: the largest set of the group, and each exhaustive search's chunks.
            primitives = primitives_per_contact(edges, max(torsions))
            check_contact_memory(max(contacts), primitives)
            for _, params, _, _ in variants:
                if "chunk" in params:
                    check_contact_memory(max(contacts), primitives, max(ms), params["chunk"])
        except OgcpError as exc:
            raise OgcpError(f"{where}.contacts: {exc}") from exc
        self.check_labels(every)
        cells = list(external)
        for obj, n, seed, m, mu, torsion, tip, (method, params, label, vwhere) in itertools.product(
            objects, contacts, seeds, ms, mus, torsions, tips, variants
        ):
            if params.get("hand") is not None:
                try:
                    resolve_hand(params["hand"]).choose_fingers(m, params.get("hand_fingers"))
                except OgcpError as exc:
                    raise OgcpError(f"{vwhere}.hand: {exc} ({where}.m includes {m})") from exc
            cells.append(
                Cell(
                    obj,
                    n,
                    seed,
                    m,
                    mu,
                    edges,
                    mesh_diagonal if obj.path else diagonal,
                    method,
                    tuple(sorted(params.items())),
                    label,
                    (group,),
                    simulate,
                    tip,
                    torsional_friction=torsion,
                )
            )
        return cells

    def external_cell(
        self,
        where: str,
        group: str,
        objects: list[ObjectSpec],
        simulate: bool,
        variant: tuple[str, dict[str, Any], str, str],
    ) -> Cell:
        """The one cell of an external grasps file: its object, contacts, best grasp's m and friction.

        The file's object must be one of the group's, so its cells sit next to the planners' on
        that object in tables and figures; the group's contact counts, seeds, m, mu and tip radii
        do not apply (the file has its own contacts and friction).

        Raises:
            OgcpError: For a file on an object the group does not list, naming both.
        """
        _, params, label, vwhere = variant
        path, grasps = self.external[params["grasps"]]
        spec = grasps.object_spec
        if spec is None or grasps.mesh is None:  # a record always names its object; arrays never reach a suite
            raise OgcpError(f"{vwhere}.grasps: {path} names no object")
        if is_object_name(grasps.mesh):
            key = spec
        elif Path(spec).is_file():
            # A mesh file is the same object wherever it lies: compared by content, as ObjectSpec.key does.
            key = f"mesh:{file_sha256(Path(spec))}"
        else:
            raise OgcpError(f"{vwhere}.grasps: the grasps' mesh file is not found: {spec}")
        matches = [o for o in objects if o.key == key]
        if not matches:
            raise OgcpError(
                f"{vwhere}.grasps: the grasps are on {grasps.mesh!r}, which {where}.objects does not list "
                f"({', '.join(o.spec for o in objects)}); add it there or move the method to a group of that object"
            )
        named = matches[0].path is None
        best = best_grasp(grasps)
        return Cell(
            matches[0],
            sum(len(g.positions) for g in grasps.grasps),
            None,
            len(grasps.grasps[best].positions),
            grasps.mu,
            grasps.cone_edges,
            grasps.diagonal if grasps.diagonal is not None or not named else DEFAULT_DIAGONAL,
            EXTERNAL_METHOD,
            tuple(sorted(params.items())),
            label,
            (group,),
            simulate,
            # 0: no reach-aware sampling, so the id and params carry no tip radius.
            0.0,
            path,
            grasps.torsional_friction,
        )

    def objects(self, where: str, value: Any) -> list[ObjectSpec]:
        if isinstance(value, str):
            value = [value]
        if not isinstance(value, list) or not value:
            raise OgcpError(f"{where}: expected a non-empty list of object names or mesh paths")
        specs = []
        for i, spec in enumerate(value):
            if not isinstance(spec, str) or not spec:
                raise OgcpError(f"{where}[{i}]: expected an object name or a mesh path, got {spec!r}")
            if "/" in spec or "\\" in spec or Path(spec).suffix.lower() in MESH_SUFFIXES:
                path = (self.base / spec).resolve()
                if not path.is_file():
                    raise OgcpError(f"{where}[{i}]: mesh file not found: {path}")
                if path.suffix.lower() not in MESH_SUFFIXES:
                    raise OgcpError(
                        f"{where}[{i}]: unsupported mesh format {path.suffix!r}; valid: {', '.join(MESH_SUFFIXES)}"
                    )
                specs.append(ObjectSpec(spec, str(path), file_sha256(path)))
            elif spec not in BUILTIN_OBJECTS and spec not in FETCHABLE_OBJECTS:
                raise choice_error(
                    f"{where}[{i}] object", spec, [*BUILTIN_OBJECTS, *FETCHABLE_OBJECTS, "<path to a mesh file>"]
                )
            else:
                specs.append(ObjectSpec(spec))
        if len({s.key for s in specs}) != len(specs):
            raise OgcpError(f"{where}: an object is listed twice")
        return specs

    def methods(self, where: str, value: Any) -> list[tuple[str, dict[str, Any], str, str]]:
        if not isinstance(value, list) or not value or not all(isinstance(t, dict) for t in value):
            raise OgcpError(f"{where}: expected one or more [[methods]] tables with a 'method' key")
        variants = []
        for i, table in enumerate(value):
            variants.extend(self.variants(f"{where}[{i}]", table))
        return variants

    def check_labels(self, variants: list[tuple[str, dict[str, Any], str, str]]) -> None:
        """One label, one method variant: plots and tables merge everything under a label.

        Variants that differ only in a seed (or in the search tree being recorded) are repeats
        of one series and may share it; across groups, a label must name the same variant too.

        Raises:
            OgcpError: Naming both entries and what tells them apart.
        """
        for method, params, label, where in variants:
            key = {k: v for k, v in params.items() if k not in UNLABELLED}
            known = self.labels.setdefault(label, (where, method, key))
            if (known[1], known[2]) != (method, key):
                other, first = _variant(method, key, known[2]), _variant(known[1], known[2], key)
                raise OgcpError(
                    f"{where}.label: {label!r} already labels {known[0]} ({first}); this entry is {other}: "
                    "give each method variant its own label (a {placeholder} fills in a swept value)"
                )

    def variants(self, where: str, table: dict[str, Any]) -> list[tuple[str, dict[str, Any], str, str]]:
        method = table.get("method")
        if method == EXTERNAL_METHOD:
            return [self.external_variant(where, table)]
        if not isinstance(method, str) or method not in METHOD_PARAMS:
            # The planners first, as everywhere; external grasps need a file too, so they are named apart.
            planners = choice_error(f"{where}.method", method, METHOD_PARAMS)
            raise OgcpError(f'{planners}; or {EXTERNAL_METHOD} with grasps = "FILE.json" (ogcp.grasps/1)')
        spec = METHOD_PARAMS[method]
        _no_unknown_keys(f"{where} (method {method})", table, ("label", "method", *spec))
        label = _string(f"{where}.label", table["label"]) if "label" in table else None
        options = []
        for key in sorted(k for k in table if k in spec):
            check = seed_values if key == "seed" else lambda w, v, p=spec[key]: values_of(w, v, p)
            values = check(f"{where}.{key}", table[key])
            if key == "hand":  # a descriptor path is relative to the suite, like a mesh
                values = [self.hand_path(str(v)) for v in values]
            options.append([(key, v) for v in values])
        variants = []
        for chosen in itertools.product(*options):
            params = complete(method, where, dict(chosen))
            variants.append((method, params, _format_label(where, label, method, params), where))
        return variants

    def hand_path(self, hand: str) -> str:
        """A hand as the cells name it: a built-in name, or its descriptor's absolute path."""
        return str((self.base / hand).resolve()) if is_descriptor_path(hand) else hand

    def external_variant(self, where: str, table: dict[str, Any]) -> tuple[str, dict[str, Any], str, str]:
        """``method = "external"``: the grasps file, read and checked now; its sha256 is the variant.

        Raises:
            OgcpError: For other keys, a missing or invalid file.
        """
        _no_unknown_keys(f"{where} (method {EXTERNAL_METHOD})", table, EXTERNAL_KEYS)
        if "grasps" not in table:
            raise OgcpError(f"{where}.grasps: missing; the path of an ogcp.grasps/1 file, relative to the suite")
        path = (self.base / _string(f"{where}.grasps", table["grasps"])).resolve()
        if not path.is_file():
            raise OgcpError(f"{where}.grasps: grasps file not found: {path}")
        try:
            grasps = load_grasps(path)
        except OgcpError as exc:
            raise OgcpError(f"{where}.grasps: {exc}") from exc
        sha = file_sha256(path)
        self.external[sha] = (str(path), grasps)
        params = {"grasps": sha}
        if "label" in table:
            label = _format_label(where, _string(f"{where}.label", table["label"]), EXTERNAL_METHOD, params)
        else:
            label = grasps.method or path.stem
        return EXTERNAL_METHOD, params, label, where

    def simulation(self, value: Any) -> dict[str, Any]:
        if not isinstance(value, dict):
            raise OgcpError("simulation: expected a [simulation] table")
        if not isinstance(value.get("enabled", False), bool):
            raise OgcpError(f"simulation.enabled: expected true or false, got {value['enabled']!r}")
        if isinstance(value.get("mu"), list):
            # The simulation takes each cell's own mu (the plan's contact set) unless this overrides it.
            raise OgcpError(
                "simulation.mu: expected one number (or leave it unset: each cell simulates with its own mu); "
                "sweep friction with the suite's mu = [...]"
            )
        # Checked even while disabled: the table is part of the suite's hash, and a typo should not
        # wait for the day the simulation is switched on.
        _check_simulation_settings(value)
        return {"enabled": False, **value}


def _variant(method: str, params: dict[str, Any], other: dict[str, Any]) -> str:
    """``method wastar eps=0.5``: the method and the parameters where it differs from ``other``."""
    differ = [f"{k}={v!r}" for k, v in sorted(params.items()) if other.get(k) != v]
    return " ".join([f"method {method}", *differ])


def _check_simulation_settings(table: dict[str, Any]) -> None:
    """Check the settings against the simulation's own validation, so a typo fails before any cell runs."""
    settings = {k: v for k, v in table.items() if k not in ("enabled", "decomposition", "max_grasps")}
    if "max_grasps" in table:
        Option("int", None, minimum=1).check("simulation.max_grasps", table["max_grasps"])
    try:
        # The settings' own modules, light: MuJoCo loads only when a cell simulates.
        from ogcp.sim_eval.decomposition.settings import DecompositionSettings
        from ogcp.sim_eval.settings import SimSettings
    except ImportError:
        return  # without the simulation installed every simulated cell records that error
    decomposition = table.get("decomposition", {})
    if not isinstance(decomposition, dict):
        raise OgcpError("simulation.decomposition: expected a [simulation.decomposition] table")
    _no_unknown_keys(
        "simulation.decomposition", decomposition, tuple(f.name for f in dataclasses.fields(DecompositionSettings))
    )
    try:
        SimSettings.from_dict(settings)
        DecompositionSettings(**decomposition)
    except OgcpError as exc:
        raise OgcpError(f"simulation: {exc}") from exc
    except (TypeError, ValueError) as exc:
        raise OgcpError(f"simulation: {str(exc).splitlines()[0]}") from exc


def _format_label(where: str, label: str | None, method: str, params: dict[str, Any]) -> str:
    if label is None:
        return default_label(method, params)
    placeholders = ", ".join("{" + k + "}" for k in params)
    try:
        for _, name, spec, _ in string.Formatter().parse(label):
            # Plain parameter names only ({seed[0]} and {seed.real} reach into values), and no
            # width or precision that would build a huge string before its length is known.
            if name is not None and name not in params:
                raise KeyError(name)
            if spec and any(int(digits) > MAX_LABEL for digits in re.findall(r"\d+", spec)):
                raise ValueError(f"width or precision in {{{name}:{spec}}} above {MAX_LABEL}")
        text = label.format(**params)
    except (KeyError, IndexError, ValueError, TypeError) as exc:
        raise OgcpError(f"{where}.label: cannot fill {label!r} ({exc}); placeholders: {placeholders}") from exc
    if len(text) > MAX_LABEL:
        raise OgcpError(f"{where}.label: {len(text)} characters; at most {MAX_LABEL}")
    return text


def _merge(cells: dict[str, Cell], cell: Cell) -> None:
    """Add a cell, or the group name to the same cell listed earlier (labels must agree)."""
    known = cells.get(cell.id)
    if known is None:
        cells[cell.id] = cell
        return
    if known.label != cell.label:
        raise OgcpError(
            f"the same run ({cell.object.spec}, n={cell.contacts}, m={cell.m}, {cell.method}) is "
            f"labelled both {known.label!r} and {cell.label!r}; give it one label"
        )
    groups = known.groups + tuple(g for g in cell.groups if g not in known.groups)
    cells[cell.id] = dataclasses.replace(known, groups=groups, simulate=known.simulate or cell.simulate)


def _no_unknown_keys(where: str, table: dict[str, Any], valid: tuple[str, ...]) -> None:
    unknown = sorted(set(table) - set(valid))
    if unknown:
        raise OgcpError(f"{where}: unknown key {unknown[0]!r}; valid keys: {', '.join(sorted(valid))}")


def _string(where: str, value: Any) -> str:
    if not isinstance(value, str):
        raise OgcpError(f"{where}: expected a string, got {value!r}")
    return value
