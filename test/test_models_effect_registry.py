# Copyright 2026 bellows_ros maintainers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""
How a package of effects becomes a registry (models/effect_registry.py): `discover`.

On the package's own two registries, and on throwaway packages written to tmp_path: every module
but `base` gives its `EFFECT`, in rank order; a wrong kind, a wrong name or a shared rank is a
TypeError naming the package or module.
"""
import importlib
import pkgutil
import sys
import uuid

import pytest

from bellows_ros.models import actuator_effects, segment_effects
from bellows_ros.models.actuator_effects.base import ActuatorEffect
from bellows_ros.models.effect_registry import discover
from bellows_ros.models.segment_effects.base import SegmentEffect

BASE = """
class Effect:
    def __init__(self, name, rank):
        self.name, self.rank = name, rank


class Other(Effect):
    pass
"""


@pytest.fixture
def package(tmp_path, monkeypatch):
    """Write a package of effect modules ({module: source}) to tmp_path; return its discover()."""
    name = f'effects_{uuid.uuid4().hex}'  # a new name: no module of another test is cached
    monkeypatch.syspath_prepend(str(tmp_path))

    def make(modules):
        root = tmp_path / name
        root.mkdir()
        (root / '__init__.py').write_text('')
        (root / 'base.py').write_text(BASE)
        for module, source in modules.items():
            (root / f'{module}.py').write_text(f'from {name}.base import Effect, Other\n{source}')
        importlib.invalidate_caches()
        kind = importlib.import_module(f'{name}.base').Effect
        return discover(name, [str(root)], kind)
    yield make
    for module in [m for m in sys.modules if m == name or m.startswith(f'{name}.')]:
        del sys.modules[module]


def test_effects_come_in_rank_order_not_name_order(package):
    effects = package({'zeta': "EFFECT = Effect('zeta', 1)\n",
                       'alpha': "EFFECT = Effect('alpha', 30)\n",
                       'mid': "EFFECT = Effect('mid', 7)\n"})
    assert isinstance(effects, tuple)
    assert [(e.name, e.rank) for e in effects] == [('zeta', 1), ('mid', 7), ('alpha', 30)]


def test_an_empty_package_is_an_empty_registry(package):
    assert package({}) == ()  # `base` alone is not an effect


def test_two_effects_with_one_rank_are_refused(package):
    with pytest.raises(TypeError, match=r'two effects share a rank \(\[1, 2, 2\]\)'):
        package({'a': "EFFECT = Effect('a', 2)\n", 'b': "EFFECT = Effect('b', 1)\n",
                 'c': "EFFECT = Effect('c', 2)\n"})


@pytest.mark.parametrize('source', ["EFFECT = Effect('leek', 1)\n",  # named otherwise
                                    'EFFECT = object()\n',             # not an effect
                                    'EFFECT = Effect\n'],              # the class itself
                         ids=['misnamed', 'not-an-effect', 'the-class'])
def test_an_effect_must_be_its_kind_and_named_as_its_module(package, source):
    with pytest.raises(TypeError, match=r"effects_.*\.leak\.EFFECT must be a Effect named 'leak'"):
        package({'leak': source, 'fine': "EFFECT = Effect('fine', 2)\n"})


def test_a_subclass_of_the_kind_is_an_effect(package):
    effects = package({'special': "EFFECT = Other('special', 1)\n"})
    assert [type(e).__name__ for e in effects] == ['Other']


@pytest.mark.parametrize('registry, kind', [(actuator_effects, ActuatorEffect),
                                            (segment_effects, SegmentEffect)],
                         ids=['actuator', 'segment'])
def test_the_packages_registries_hold_every_module_in_rank_order(registry, kind):
    modules = {m.name for m in pkgutil.iter_modules(registry.__path__)} - {'base'}
    assert {effect.name for effect in registry.EFFECTS} == modules
    ranks = [effect.rank for effect in registry.EFFECTS]
    assert ranks == sorted(set(ranks))
    assert all(isinstance(effect, kind) for effect in registry.EFFECTS)
    assert discover(registry.__name__, registry.__path__, kind) == registry.EFFECTS
