"""Q1 speed against scipy's ConvexHull, measured in the same run (issue targets 1 and 2).

Run: ``python -m ogcp.benchmarks.studies.q1_speed [--grasps 300] [--repeats 5]``. Prints per-input medians
and the ratio scipy / ogcp; values must agree within 1e-9 (checked). With ``--es-chunks K`` it
instead times K exhaustive-search chunks spread over all C(1000, 3) grasps per object and
extrapolates the CPU time of the full search.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from ogcp.planner import builtin_mesh, sample_contacts
from ogcp.planner.baselines import combinations
from ogcp.planner.baselines.es import _chunk_task
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.grasp.kernel import FALLBACK, default_directions, support_table
from ogcp.planner.grasp.quality import exact_q1_batch, q1, q1_certificate


def scipy_q1(w: np.ndarray) -> float:
    try:
        value = float((-ConvexHull(w).equations[:, -1]).min())
    except QhullError:
        return 0.0
    return value if value > 1e-9 else 0.0


def median_seconds(function, inputs, repeats: int) -> float:
    """Median over repeats of the mean time per input [s]."""
    runs = []
    for _ in range(repeats):
        start = time.perf_counter()
        for x in inputs:
            function(x)
        runs.append((time.perf_counter() - start) / len(inputs))
    return statistics.median(runs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grasps", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--objects", default="box,sphere,donut,amphora")
    parser.add_argument(
        "--es-chunks",
        type=int,
        default=0,
        help="also time this many ES chunks spread over all C(1000, 3) grasps, per object",
    )
    parser.add_argument("--es-chunk-size", type=int, default=20_000)
    args = parser.parse_args()
    if args.es_chunks:
        print("| object | ES chunks timed | grasps | CPU s | CPU us per grasp | full ES, 1 core | full ES, 2 workers |")
        print("|---|---|---|---|---|---|---|")
        for name in args.objects.split(","):
            print(es_extrapolation(name, args.es_chunks, args.es_chunk_size), flush=True)
        return
    print("| object | input | ogcp median | scipy median | ratio scipy/ogcp | max abs diff |")
    print("|---|---|---|---|---|---|")
    batch_rows = []
    for name in args.objects.split(","):
        contacts = sample_contacts(builtin_mesh(name), 1000, seed=0)
        rng = np.random.default_rng(0)
        small = [contacts.subset_wrenches(rng.choice(1000, 3, replace=False)) for _ in range(args.grasps)]
        large = [contacts.subset_wrenches(rng.choice(1000, 100, replace=False))]
        for label, inputs, repeats in (("3-contact grasp", small, args.repeats), ("100-contact set", large, 1)):
            diff = max(abs(q1(w) - scipy_q1(w)) for w in inputs)
            ours = median_seconds(q1, inputs, repeats)
            ref = median_seconds(scipy_q1, inputs, repeats)
            print(f"| {name} | {label} | {ours * 1e3:.3f} ms | {ref * 1e3:.3f} ms | {ref / ours:.1f}x | {diff:.1e} |")
        batch_rows.append(batch_throughput(name, contacts, small, args.grasps, args.repeats))
        start = time.perf_counter()
        q_ows = q1_certificate(contacts.wrenches.reshape(-1, 6)).q1
        print(f"| {name} | Q_OWS of 1000 contacts | {time.perf_counter() - start:.2f} s | | | Q_OWS = {q_ows:.6f} |")
    print("\nBatched 3-contact grasps, per grasp, same grasps as above (the ES path: compiled batch with")
    print("the canonical refit in compiled code, qhull for whatever the kernel leaves):\n")
    print("| object | force closure | kernel fallbacks | ES path per grasp | scipy loop per grasp | ratio scipy/ES |")
    print("|---|---|---|---|---|---|")
    print("\n".join(batch_rows))


def batch_throughput(name: str, contacts: ContactSet, small: list[np.ndarray], count: int, repeats: int) -> str:
    """What ES does per grasp (:func:`exact_q1_batch`) against a scipy loop on the same grasps."""
    rng = np.random.default_rng(0)
    grasps = np.array([rng.choice(1000, 3, replace=False) for _ in range(count)])
    wrenches = np.asarray(contacts.wrenches)
    table = support_table(wrenches, default_directions())
    values, status = exact_q1_batch(wrenches, grasps, table)  # compile / load outside the timing
    reference = np.array([scipy_q1(contacts.subset_wrenches(g)) for g in grasps])
    diff = float(np.max(np.abs(values - reference)))
    if diff > 1e-9:
        raise AssertionError(f"{name}: batched Q1 differs from scipy by {diff:.1e}")
    inner = 10  # one batch call is short: time several per repeat
    es_path = median_seconds(lambda _: [exact_q1_batch(wrenches, grasps, table) for _ in range(inner)], [None], repeats)
    es_path /= inner * count
    ref = median_seconds(scipy_q1, small, repeats)
    return (
        f"| {name} | {np.mean(values > 0):.0%} | {int(np.sum(status == FALLBACK))} | {es_path * 1e6:.1f} us | "
        f"{ref * 1e6:.0f} us | {ref / es_path:.0f}x |"
    )


def es_extrapolation(name: str, chunks: int, size: int) -> str:
    """CPU time of ES chunks at evenly spread lexicographic ranks, extrapolated to all grasps."""
    contacts = sample_contacts(builtin_mesh(name), 1000, seed=0)
    total = combinations.count(1000, 3)
    n_chunks = -(-total // size)
    edges = np.linspace(0.0, 1.0, 51)
    _chunk_task(contacts, 3, 0, 64, edges, False)  # compile / load outside the timing
    cpu = evaluated = 0.0
    for index in np.linspace(0, n_chunks - 1, chunks).round().astype(int):
        result = _chunk_task(contacts, 3, int(index), size, edges, False)
        cpu += result.cpu_seconds
        evaluated += result.evaluated
    per = cpu / evaluated
    return (
        f"| {name} | {chunks} x {size} | {int(evaluated)} | {cpu:.1f} | {per * 1e6:.2f} | "
        f"{per * total / 60:.1f} min | {per * total / 120:.1f} min |"
    )


if __name__ == "__main__":
    main()
