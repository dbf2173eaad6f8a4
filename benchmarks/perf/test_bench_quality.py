"""Q1 speed: ogcp's engine against the scipy ConvexHull reference on the same inputs."""

from __future__ import annotations

from ogcp.benchmarks.studies.q1_speed import scipy_q1
from ogcp.planner.grasp.kernel.ray_bound import facet_bound
from ogcp.planner.grasp.quality import q1


def test_small_grasps_ogcp(benchmark, small_grasps):
    benchmark.group = "q1-small"
    values = benchmark(lambda: [q1(w) for w in small_grasps])
    assert len(values) == len(small_grasps)


def test_small_grasps_scipy(benchmark, small_grasps):
    benchmark.group = "q1-small"
    benchmark(lambda: [scipy_q1(w) for w in small_grasps])


def test_super_contact_ogcp(benchmark, super_contact):
    benchmark.group = "q1-large"
    assert benchmark(q1, super_contact) > 0


def test_super_contact_scipy(benchmark, super_contact):
    benchmark.group = "q1-large"
    benchmark.pedantic(scipy_q1, args=(super_contact,), rounds=1, iterations=1)


def test_small_grasps_batched_kernel(benchmark, box1000):
    import numpy as np

    from ogcp.planner.grasp.kernel import default_directions, q1_batch, support_table

    benchmark.group = "q1-small"
    rng = np.random.default_rng(0)
    grasps = np.array([rng.choice(1000, 3, replace=False) for _ in range(100)])
    wrenches = np.asarray(box1000.wrenches)
    table = support_table(wrenches, default_directions())
    values, ok = benchmark(q1_batch, wrenches, grasps, table=table)
    assert ok.all() and len(values) == 100


def test_sphere_grasps_es_path(benchmark, sphere1000):
    """What ES does per grasp on the sphere (half the grasps in force closure, canonical refit)."""
    import numpy as np

    from ogcp.planner.grasp.kernel import default_directions, support_table
    from ogcp.planner.grasp.quality import exact_q1_batch

    benchmark.group = "q1-small"
    rng = np.random.default_rng(0)
    grasps = np.array([rng.choice(1000, 3, replace=False) for _ in range(300)])
    wrenches = np.asarray(sphere1000.wrenches)
    table = support_table(wrenches, default_directions())
    values, _ = benchmark(exact_q1_batch, wrenches, grasps, table)
    assert np.mean(values > 0) > 0.3


def test_mid_unions_exact(benchmark, mid_unions):
    benchmark.group = "q1-mid"
    values = benchmark(lambda: [q1(w) for w, _ in mid_unions])
    assert min(values) >= 0


def test_mid_unions_facet_bound(benchmark, mid_unions):
    """The upper bound the search tries before an exact value (one start direction)."""
    benchmark.group = "q1-mid"
    bounds = benchmark(lambda: [facet_bound(w, start)[0] for w, start in mid_unions])
    assert all(b >= q1(w) - 1e-12 for b, (w, _) in zip(bounds, mid_unions, strict=True))
