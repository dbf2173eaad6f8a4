"""The readable summaries that ``ogcp plan`` prints (``--json`` prints the record instead)."""

from __future__ import annotations

import numpy as np

from ogcp.planner.baselines.es import ESResult
from ogcp.planner.baselines.hfts import HFTSResult
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.infra.tolerance import TOL
from ogcp.planner.methods.registry import METHODS
from ogcp.planner.methods.runners import MethodRun
from ogcp.planner.records.plan import PlanHand, PlanOptimum, PlanView
from ogcp.planner.search.result import UNFINISHED, SearchResult


def _soft_text(contacts: ContactSet) -> str:
    """``   soft fingers, torsion 0.02 m`` for soft contacts; nothing for hard ones."""
    if contacts.torsional_friction <= 0:
        return ""
    return f"   soft fingers, torsion {contacts.torsional_friction:g} m"


def describe(run: MethodRun, contacts: ContactSet) -> str:
    """Readable multi-line summary of any method's run."""
    plan = PlanView(run.record)
    if isinstance(run.result, ESResult):
        text = es_summary(run.result, contacts)
    elif isinstance(run.result, HFTSResult):
        text = hfts_summary(run.result, contacts) + _optimum_text(run.result, plan.optimum)
    else:
        text = search_summary(run.result, contacts) + _hand_text(plan.hand)
    return (
        text
        + _realise_text(run.record.get("realise"))
        + _closure_note(run.result.q1, len(run.result.grasp), contacts, plan.hand is not None)
    )


def _realise_text(block: object) -> str:
    """A line on ``--realise``: which plan the hand's fit realised, and how many it rejected."""
    if not isinstance(block, dict):
        return ""
    rejected = block.get("rejected") or []
    verdict = "realised by the hand's fit" if block.get("realised") else "NOT realised by the hand's fit either"
    return f"\nrealise: plan {block.get('attempts')} {verdict}; {len(rejected)} grasp(s) rejected before it" + (
        "" if not rejected else f" (first: {rejected[0].get('grasp')}, {rejected[0].get('reason')})"
    )


def _closure_note(q1: float, m: int, contacts: ContactSet, hand: bool) -> str:
    """A line saying what to change when the answer cannot resist every wrench (Q1 = 0), else nothing."""
    if q1 > 0:
        return ""
    if m == 2 and contacts.torsional_friction <= 0:
        remedy = "two hard contacts never resist a torsion about their line: plan with --contact-model soft"
    elif hand:
        remedy = (
            "none of the grasps the hand can reach on these contacts is in force closure: sample more "
            "contacts (-n), choose other fingers (--hand-fingers), or scale the object to the hand (--diagonal)"
        )
    else:
        remedy = "no grasp the search admits is in force closure: sample more contacts (-n) or relax the constraints"
    return f"\nnote: Q1 = 0, the grasp resists no wrench in some direction; {remedy}"


def search_summary(result: SearchResult, contacts: ContactSet) -> str:
    """Readable multi-line summary of an A*, WA* or Dijkstra plan."""
    s, c = result.stats, result.config
    heuristic = f"Γh={c['heuristic']} b={c['heuristic_branching']}" if c["heuristic"] != "none" else "no heuristic"
    method = METHODS[result.method].title + (f" (eps={result.eps:g})" if result.method == "wastar" else "")
    if result.status in UNFINISHED:
        why = {"stopped": "stopped at its time limit", "memory": "stopped at its memory limit"}
        relative = result.gap / result.bound if result.bound > 0 else 0.0
        certificate = (
            f"{why.get(result.status, 'interrupted by request')}: best so far, optimum <= {result.bound:.6f} "
            f"(gap {result.gap:.6f}, {100 * relative:.2f} % of the bound)"
        )
    elif result.method == "wastar" and result.bound - result.q1 > TOL.q1_gap * max(1.0, result.bound):
        certificate = f"within bound: optimum <= {result.bound:.6f} (guarantee: <= {result.eps_bound:.6f})"
    elif result.method == "wastar":  # its bound closed on its grasp: proven optimal like A*'s
        certificate = "optimal (certified: the bound equals Q1)"
    elif c["symmetry"]:
        certificate = "optimal up to approximate symmetry removal"
    else:
        certificate = "optimal (certified)"
    lines = [
        (
            f"{_object_text(contacts)}   mu = {contacts.mu:g}   k = {contacts.cone_edges}{_soft_text(contacts)}"
            f"   seed = {c['seed']}"
        ),
        f"search: {method}, m = {c['m']}, Γ={c['successor']} b={c['branching']}, {heuristic}"
        + (", symmetry removal" if c["symmetry"] else ""),
        f"grasp: {list(result.grasp)}   Q1 = {result.q1:.6f}   Q_OWS = {result.q_ows:.6f}",
        f"certificate: {certificate}",
        (
            f"states: created {s.created}, visited {s.visited}, b* = {s.effective_branching_factor:.2f}, "
            f"solution depth {s.solution_depth}"
        ),
        f"created per level: {list(s.created_per_level)}",
        f"visited per level: {list(s.visited_per_level)}",
        (
            f"Q1 evaluations: {s.q1_evaluations} (cache hits {s.q1_cache_hits}, rejected by bound {s.bound_rejections}), "
            f"hull calls {s.hull_calls}, facet bounds {s.facet_bounds}"
        ),
        f"time: {s.wall_seconds:.2f} s wall, {s.cpu_seconds:.2f} s CPU; peak memory {s.peak_rss_bytes / 2**20:.0f} MiB",
        "contacts (index: position [m] / inward normal):",
    ]
    for i, p, n in zip(result.grasp, result.positions, result.normals):
        lines.append(f"  {i:5d}: [{p[0]:+.4f} {p[1]:+.4f} {p[2]:+.4f}] / [{n[0]:+.3f} {n[1]:+.3f} {n[2]:+.3f}]")
    return "\n".join(lines)


def es_summary(result: ESResult, contacts: ContactSet) -> str:
    """Readable summary of an exhaustive search."""
    lines = [
        _object_text(contacts),
        (
            f"search: {result.method}, m = {result.config['m']}, {result.grasps} grasps in {result.chunks} chunks "
            f"({result.resumed} resumed), backend {result.config['backend']}"
        ),
        f"grasp: {list(result.grasp)}   Q1 = {result.q1:.6f}   Q_OWS = {result.q_ows:.6f}",
    ]
    covered = result.grasps if result.evaluated is None else result.evaluated
    if result.status == "stopped":
        lines.append(
            f"certificate: stopped at its time limit after {covered} of {result.grasps} grasps "
            f"({100 * covered / result.grasps:.3g} %): best of those, optimum <= Q_OWS = {result.bound:.6f}"
        )
    admissible = covered - result.excluded
    if result.excluded:
        lines.append(f"constraints: {result.excluded} grasps excluded, {admissible} admissible")
    if (
        result.counts is not None
        and result.zero is not None
        and result.force_closure_fraction is not None
        and admissible
    ):
        lines.append(
            f"force closure: {admissible - result.zero} of {admissible} "
            f"({100 * result.force_closure_fraction:.2f} %); histogram over (0, Q_OWS]: {result.counts.tolist()}"
        )
    lines.append(
        f"exact evaluations: {result.exact_evaluations}; time: {result.wall_seconds:.2f} s wall, "
        f"{result.cpu_seconds:.2f} s CPU (all workers)"
    )
    return "\n".join(lines)


def hfts_summary(result: HFTSResult, contacts: ContactSet) -> str:
    """Readable summary of the HFTS runs."""
    s = result.summary()
    lines = [
        _object_text(contacts),
        (
            f"search: HFTS, m = {result.config['m']}, {s['runs']} runs (seeds {result.config['seed']}.."
            f"{result.config['seed'] + s['runs'] - 1}), {result.config['levels']} cluster levels"
        ),
        f"best run: grasp {list(result.grasp)}   Q1 = {result.q1:.6f}   Q_OWS = {result.q_ows:.6f}",
        (
            f"spread: mean {s['mean']:.6f}  std {s['std']:.6f}  max {s['max']:.6f}  "
            f"force closure {100 * s['force_closure_fraction']:.0f} %"
        ),
        f"Q1 evaluations: {s['q1_evaluations']}; time: {s['wall_seconds']:.2f} s wall, {s['cpu_seconds']:.2f} s CPU",
        "runs (seed: Q1):  " + "  ".join(f"{r.seed}: {r.q1:.4f}" for r in result.runs),
    ]
    stopped = sum(r.stopped for r in result.runs)
    if stopped:
        lines.insert(
            3, f"stopped at its time limit: {stopped} of {s['runs']} runs cut short (they descend without moves)"
        )
    return "\n".join(lines)


def _object_text(contacts: ContactSet) -> str:
    """``object: NAME   |C| = n``, with the fingertip radius the contacts were kept for when there is one."""
    source = contacts.source
    what = source.get("name") or source.get("path") or "contact file"
    tip = source.get("tip_radius")
    reach = f"   tip r = {tip:.4g} m" if isinstance(tip, int | float) and tip > 0 else ""
    return f"object: {what}   |C| = {len(contacts)}{reach}"


def _optimum_text(result: HFTSResult, optimum: PlanOptimum | None) -> str:
    if optimum is None or optimum.q1 is None or optimum.grasp is None:
        return ""
    if optimum.status != "optimal":
        bound = "" if optimum.bound is None else f", optimum <= {optimum.bound:.6f}"
        return (
            f"\nA* optimum: not proven in the time it had (its best grasp {list(optimum.grasp)}   "
            f"Q1 = {optimum.q1:.6f}{bound})"
        )
    gaps = optimum.q1 - result.values
    return (
        f"\nA* optimum: grasp {list(optimum.grasp)}   Q1 = {optimum.q1:.6f}   "
        f"HFTS gap: best {gaps.min():.6f}, mean {gaps.mean():.6f}, "
        f"runs reaching it {int(np.sum(gaps <= 0))} of {len(gaps)}"
    )


def _hand_text(hand: PlanHand | None) -> str:
    if hand is None:
        return ""
    residual = "n/a" if hand.residual is None else f"{hand.residual:.3f}"
    if hand.fingers and len(hand.fingers) == len(hand.finger_contacts):
        placed = ", ".join(f"{f} on {c}" for f, c in zip(hand.fingers, hand.finger_contacts, strict=True))
    else:
        placed = f"fingers on contacts {list(hand.finger_contacts)}"
    angles = [round(a, 3) for a in hand.joint_angles]
    names = f" ({', '.join(hand.joint_names)})" if len(hand.joint_names) == len(angles) else ""
    return f"\nhand: {hand.name}, residual {residual}, {placed}, nearest sampled joint angles{names} {angles}"
