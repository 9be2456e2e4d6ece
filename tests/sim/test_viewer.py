"""The interactive viewer option: refused, naming the device and the parameter, without a display."""

from __future__ import annotations

import pytest

import dgraph as dg
from dgraph_sim import viewer
from dgraph_sim.device import MujocoDevice


def test_without_a_display_the_viewer_is_refused_naming_the_entity_and_the_parameter(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(viewer.sys, "platform", "linux")
    assert not viewer.display_available()
    with pytest.raises(dg.ParamError, match=r"arm: parameter 'viewer': no display: DISPLAY and WAYLAND_DISPLAY "
                                            r"are unset") as info:
        MujocoDevice("arm", model="panda", viewer=True, dt=0.001)
    assert info.value.entity == "arm"
    assert MujocoDevice("arm", model="panda", dt=0.001)._viewer is None  # the default: no window


def test_a_display_variable_is_enough_to_try(monkeypatch):
    monkeypatch.setattr(viewer.sys, "platform", "linux")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.setenv("WAYLAND_DISPLAY", "wayland-0")
    assert viewer.display_available()
