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
What the launch files share (runtime/managed_launch.py), built and inspected, never launched.

`own_session` finds setsid on the PATH (a PATH of the test's own); `bring_to_active`'s actions
are taken apart: the configure it emits, and the two event handlers it registers, each asked
whether it handles the driver's lifecycle transition events (made here as launch_ros makes them
from the node's `transition_event` topic) and what it does then. The launches themselves run in
test_launch.py. launch_ros comes with the ROS 2 command line: where that is absent the module
skips, as the command line's tests do (node_processes.require_ros2_cli), unless
BELLOWS_REQUIRE_ROS2_CLI=1.
"""
import os

import pytest

try:
    from launch import LaunchContext
    from launch.actions import EmitEvent, OpaqueFunction, RegisterEventHandler
    from launch_ros.actions import LifecycleNode
    from launch_ros.events.lifecycle import ChangeState, StateTransition
    from lifecycle_msgs.msg import State, Transition, TransitionEvent

    from bellows_ros.runtime.managed_launch import bring_to_active, own_session
except ImportError as missing:
    if os.environ.get('BELLOWS_REQUIRE_ROS2_CLI') == '1':
        raise
    pytest.skip(f'launch_ros not importable ({missing}): source your ROS 2 setup.bash',
                allow_module_level=True)


class Launched(LifecycleNode):
    """A LifecycleNode action as it is once launch has executed it: its name resolved."""

    node_name = '/driver_node'


def node(name='driver_node'):
    return Launched(package='bellows_ros', executable=name, name=name, namespace='')


def transition(action, start, goal):
    """Return the StateTransition event launch_ros makes of `action`'s transition event."""
    return StateTransition(action=action, msg=TransitionEvent(
        transition=Transition(label='transition'), start_state=State(label=start),
        goal_state=State(label=goal)))


def change_state(action, transition_id, target):
    """Check that `action` emits the change `transition_id` for `target`, no other node."""
    assert isinstance(action, EmitEvent) and isinstance(action.event, ChangeState)
    assert action.event.transition_id == transition_id
    assert action.event.lifecycle_node_matcher(target)
    assert not action.event.lifecycle_node_matcher(node('other_node'))


def test_own_session_is_the_setsid_on_the_path(tmp_path, monkeypatch):
    tools = tmp_path / 'bin'
    tools.mkdir()
    setsid = tools / 'setsid'
    setsid.write_text('#!/bin/sh\nexec "$@"\n')
    setsid.chmod(0o755)
    monkeypatch.setenv('PATH', str(tools))
    assert own_session() == str(setsid)


def test_without_setsid_a_node_gets_no_prefix(tmp_path, monkeypatch):
    monkeypatch.setenv('PATH', str(tmp_path))  # a directory without setsid
    assert own_session() is None


def test_the_launch_emits_configure_for_the_node_last():
    driver = node()
    actions = bring_to_active(driver)
    assert [type(a) for a in actions] == [RegisterEventHandler, RegisterEventHandler, EmitEvent]
    # the handlers are registered before the configure that would trigger them
    change_state(actions[-1], Transition.TRANSITION_CONFIGURE, driver)


def test_the_node_reaching_inactive_is_activated():
    driver = node()
    activate = bring_to_active(driver)[0].event_handler
    assert activate.matches(transition(driver, 'configuring', 'inactive'))
    # only this node's, and only on reaching inactive
    assert not activate.matches(transition(node('other_node'), 'configuring', 'inactive'))
    assert not activate.matches(transition(driver, 'activating', 'active'))
    assert not activate.matches(transition(driver, 'configuring', 'unconfigured'))
    [emit] = activate.entities
    change_state(emit, Transition.TRANSITION_ACTIVATE, driver)


def test_a_configure_that_fails_ends_the_launch_with_an_error_naming_the_node():
    driver = node()
    failed = bring_to_active(driver)[1].event_handler
    assert failed.matches(transition(driver, 'configuring', 'unconfigured'))
    # a cleanup also ends unconfigured: that is no failure; nor is another node's configure
    assert not failed.matches(transition(driver, 'cleaningup', 'unconfigured'))
    assert not failed.matches(transition(node('other_node'), 'configuring', 'unconfigured'))
    assert not failed.matches(transition(driver, 'configuring', 'inactive'))
    [end] = failed.entities
    assert isinstance(end, OpaqueFunction)
    # raising is what makes `ros2 launch` stop every node and exit non-zero
    with pytest.raises(RuntimeError) as error:
        end.execute(LaunchContext())
    assert str(error.value) == 'driver_node could not be configured; see its output above'
