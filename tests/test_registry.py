"""The entity-type registry: plugins load one by one, a broken one is reported, not contagious."""

from __future__ import annotations

import sys
from importlib.metadata import EntryPoint

import pytest

import dgraph as dg
from dgraph import registry

BROKEN = '''
from pathlib import Path
Path(__file__).with_suffix(".imports").open("a").write("imported\\n")
import dgraph as dg

@dg.register(name="TestOnlyBeforeTheFailure")
class BeforeTheFailure(dg.Entity):
    """Registered, then its module fails."""

raise ImportError("libfoo.so.1: cannot open shared object file")
'''

GOOD = '''
import dgraph as dg

@dg.register(name="TestOnlyFromTheGoodFamily")
class FromTheGoodFamily(dg.Entity):
    """A type of the family listed after the broken one."""
'''


@pytest.fixture
def plugins(tmp_path, monkeypatch):
    """The entry points ``broken`` then ``good`` (modules written to ``tmp_path``), on a registry
    that has loaded nothing yet (its real types kept, restored afterwards)."""
    (tmp_path / "dgraph_test_broken_family.py").write_text(BROKEN)
    (tmp_path / "dgraph_test_good_family.py").write_text(GOOD)
    monkeypatch.syspath_prepend(str(tmp_path))
    points = [EntryPoint("broken", "dgraph_test_broken_family", registry.ENTRY_POINT_GROUP),
              EntryPoint("good", "dgraph_test_good_family", registry.ENTRY_POINT_GROUP)]
    monkeypatch.setattr(registry, "entry_points", lambda group: [p for p in points if p.group == group])
    monkeypatch.setattr(registry, "_TYPES", dict(registry._TYPES))
    monkeypatch.setattr(registry, "_plugins_loaded", False)
    monkeypatch.setattr(registry, "_TRIED", set())
    monkeypatch.setattr(registry, "_FAILED", {})
    yield tmp_path / "dgraph_test_broken_family.imports"
    for name in ("dgraph_test_broken_family", "dgraph_test_good_family"):
        sys.modules.pop(name, None)


def test_a_broken_plugin_does_not_hide_the_families_after_it(plugins):
    assert dg.get_type("TestOnlyFromTheGoodFamily").__name__ == "FromTheGoodFamily"
    assert "TestOnlyFromTheGoodFamily" in dg.entity_types()
    assert "TestOnlyBeforeTheFailure" in dg.entity_types()  # what it registered before failing stays


def test_a_broken_plugin_is_reported_with_its_own_error_when_a_type_is_not_found(plugins):
    with pytest.raises(dg.RegistryError) as err:
        dg.get_type("TestOnlyFromTheBrokenFamily")
    message = str(err.value)
    assert message.startswith("unknown entity type 'TestOnlyFromTheBrokenFamily'")
    assert "entity plugin 'broken' (dgraph_test_broken_family) failed to load: ImportError: " \
           "libfoo.so.1: cannot open shared object file" in message
    assert isinstance(err.value.__cause__, ImportError)
    assert registry.plugin_errors() == {"broken": "entity plugin 'broken' (dgraph_test_broken_family) failed to "
                                                  "load: ImportError: libfoo.so.1: cannot open shared object file"}


def test_each_plugin_is_imported_once_even_if_it_failed(plugins):
    for _ in range(3):
        with pytest.raises(dg.RegistryError):
            dg.get_type("TestOnlyNowhere")
        dg.entity_types()
    assert plugins.read_text() == "imported\n"


def test_an_unknown_type_names_no_plugin_when_none_failed(monkeypatch):
    import dgraph.entities.operators  # noqa: F401  (registers Gain)

    monkeypatch.setattr(registry, "entry_points", lambda group: [])
    monkeypatch.setattr(registry, "_plugins_loaded", False)
    monkeypatch.setattr(registry, "_FAILED", {})
    with pytest.raises(dg.RegistryError) as err:
        dg.get_type("Gian")
    assert str(err.value) == "unknown entity type 'Gian'; did you mean Gain?"
    assert err.value.__cause__ is None
