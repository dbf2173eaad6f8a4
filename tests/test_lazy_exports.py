"""The packages that load their names on first use (PEP 562) still export every name they list.

Their ``__init__`` files map each public name to its module instead of importing it, so that
``ogcp --help`` and light readers (settings, defaults) do not load numpy, trimesh, scipy or the
numba kernels. A name missing from the map, or mapped to the wrong module, would only fail when
first used; these tests use every one.
"""

from __future__ import annotations

import importlib
import pickle

import pytest

LAZY_PACKAGES = (
    "ogcp.benchmarks",
    "ogcp.planner",
    "ogcp.planner.grasp",
    "ogcp.planner.methods",
    "ogcp.planner.objects",
    "ogcp.sim_eval",
    "ogcp.sim_eval.decomposition",
    "ogcp.benchmarks.plots",
)


@pytest.mark.parametrize("name", LAZY_PACKAGES)
def test_every_listed_name_resolves_to_its_module_object(name):
    package = importlib.import_module(name)
    exports = package._EXPORTS
    assert sorted(package.__all__) == sorted(exports)
    for public, module in exports.items():
        assert getattr(package, public) is getattr(importlib.import_module(module), public)
    assert set(package.__all__) <= set(dir(package))


@pytest.mark.parametrize("name", LAZY_PACKAGES)
def test_unknown_name_is_an_attribute_error(name):
    package = importlib.import_module(name)
    with pytest.raises(AttributeError, match="no_such_name"):
        package.no_such_name  # noqa: B018


def test_a_submodule_never_hides_the_function_of_its_name():
    import ogcp.sim_eval.decomposition

    module = importlib.import_module("ogcp.sim_eval.decomposition.decompose")  # binds the submodule, once
    assert ogcp.sim_eval.decomposition.decompose is module.decompose
    assert callable(ogcp.sim_eval.decomposition.decompose)


def test_method_specs_pickle_with_their_deferred_runners():
    from ogcp.planner.methods.registry import METHODS

    for spec in METHODS.values():
        assert pickle.loads(pickle.dumps(spec)) == spec
