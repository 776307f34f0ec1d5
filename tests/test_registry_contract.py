"""The built-in estimators fulfil the plugin contract of mcgeom.registry.

Each registered hook is checked against the parameters of its protocol
(``Estimator``, ``MinimalSolver``, ``Sampler``, ``Proposer``, ``Objective``): it
must accept exactly the protocol's positional arguments (the robust layer
passes them so) and require nothing more, and the estimator must accept each
documented option as a keyword. A hook whose signature drifts fails here
rather than inside a RANSAC run.
"""

from __future__ import annotations

import inspect

import pytest

import mcgeom  # noqa: F401  (registers the built-ins)
from mcgeom import registry

HOOKS = {"func": registry.Estimator, "minimal_solver": registry.MinimalSolver,
         "sampler": registry.Sampler, "proposer": registry.Proposer,
         "objective": registry.Objective}

BUILTINS = [info for info in registry.list_estimators()
            if getattr(info.func, "__module__", "").startswith("mcgeom.")]


def _protocol_positional(protocol) -> int:
    """Number of positional parameters of the protocol's ``__call__`` (without self)."""
    params = list(inspect.signature(protocol.__call__).parameters.values())[1:]
    return sum(p.kind is inspect.Parameter.POSITIONAL_ONLY for p in params)


def test_builtins_are_registered():
    assert {i.name for i in BUILTINS} >= {"linear17", "refine", "five_plus_one", "e_socp",
                                          "bnb_lp", "known_rotation_translation"}


def test_protocol_arity():
    """The contract itself, as the robust layer calls the hooks."""
    assert [_protocol_positional(HOOKS[k]) for k in HOOKS] == [1, 1, 2, 4, 2]


@pytest.mark.parametrize("info", BUILTINS, ids=lambda i: i.name)
def test_hooks_match_their_protocol(info):
    assert isinstance(info.min_sample, int) and info.min_sample >= 1
    assert info.func is not None
    for field, protocol in HOOKS.items():
        hook = getattr(info, field)
        if hook is None:
            continue
        sig = inspect.signature(hook)
        n = _protocol_positional(protocol)
        sig.bind(*[object()] * n)          # TypeError: a missing or extra required one
        with pytest.raises(TypeError):     # and no more positional ones than promised
            sig.bind(*[object()] * (n + 1))
    fsig = inspect.signature(info.func)
    fsig.bind(object(), **{k: None for k in info.options})


@pytest.mark.parametrize("info", BUILTINS, ids=lambda i: i.name)
def test_info_fulfils_the_plugin_protocol(info):
    """Every attribute :class:`registry.EstimatorPlugin` declares is present."""
    for name in registry.EstimatorPlugin.__annotations__:
        assert hasattr(info, name), name
