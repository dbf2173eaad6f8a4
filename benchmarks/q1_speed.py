"""Q1 speed against scipy's ConvexHull, measured in the same run (issue targets 1 and 2).

Run: ``python -m benchmarks.q1_speed [--grasps 300] [--repeats 5]``. Prints per-input medians
and the ratio scipy / ogcp; values must agree within 1e-9 (checked).
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from planner import builtin_mesh, sample_contacts
from planner.kernel import default_directions, q1_batch, support_table
from planner.quality import q1, q1_certificate


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
    args = parser.parse_args()
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
    print("\nBatched 3-contact grasps (the ES path), per grasp, same grasps as above:\n")
    print("| object | kernel batch | batch + canonical refit | scipy loop | ratio (kernel) | ratio (with refit) |")
    print("|---|---|---|---|---|---|")
    print("\n".join(batch_rows))


def batch_throughput(name: str, contacts, small: list[np.ndarray], count: int, repeats: int) -> str:
    """The batched path ES uses, on the same grasps: kernel only, and with the canonical refit."""
    rng = np.random.default_rng(0)
    grasps = np.array([rng.choice(1000, 3, replace=False) for _ in range(count)])
    wrenches = np.asarray(contacts.wrenches)
    table = support_table(wrenches, default_directions())
    q1_batch(wrenches, grasps[:8], table=table)  # compile / load outside the timing

    def kernel_only() -> None:
        q1_batch(wrenches, grasps, table=table)

    def with_refit() -> None:
        values, ok = q1_batch(wrenches, grasps, table=table)
        for i in np.flatnonzero(~ok | (values > 0)):
            q1(wrenches[grasps[i]].reshape(-1, 6))

    raw = median_seconds(lambda _: kernel_only(), [None], repeats) / count
    refit = median_seconds(lambda _: with_refit(), [None], repeats) / count
    ref = median_seconds(scipy_q1, small, 1)
    return (f"| {name} | {raw * 1e6:.1f} us | {refit * 1e6:.1f} us | {ref * 1e6:.0f} us | "
            f"{ref / raw:.0f}x | {ref / refit:.0f}x |")


if __name__ == "__main__":
    main()
