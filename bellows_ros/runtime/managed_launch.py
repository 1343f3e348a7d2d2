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
What the launch files share (launch_ros needed): managed nodes to `active`, nodes' sessions.

Each node gets a session of its own (`own_session`). A managed node is brought to `active` as
ros2/demos' lifecycle launch does (`bring_to_active`): emit `configure` for the node, and
`activate` when it reaches `inactive`. A configure that fails (a device absent) returns the
node to `unconfigured`: the launch then stops with an error instead of running a graph without
its driver (the nodes' own output says why).
"""
import shutil

from launch.actions import EmitEvent, OpaqueFunction, RegisterEventHandler
from launch.events import matches_action
from launch_ros.event_handlers import OnStateTransition
from launch_ros.events.lifecycle import ChangeState
from lifecycle_msgs.msg import Transition


def own_session():
    """
    Return the `prefix` that starts a node in a session of its own ('setsid'), or None.

    A session of its own is a scheduler autogroup of its own (docs/nodes.md, "Timing"). A process
    launch starts stays in launch's process group, no group leader, so setsid makes the session
    and execs the node in place: no fork, and launch still signals the node itself. None where
    util-linux' setsid is absent.
    """
    return shutil.which('setsid')


def bring_to_active(node):
    """Return the actions taking LifecycleNode action `node` to active, or ending the launch."""
    def change(transition_id):
        return EmitEvent(event=ChangeState(lifecycle_node_matcher=matches_action(node),
                                           transition_id=transition_id))

    def failed(context):
        # Raising is how a launch file makes `ros2 launch` exit non-zero; every node is stopped.
        raise RuntimeError(f'{node.node_name.lstrip("/")} could not be configured; see its '
                           'output above')

    return [
        RegisterEventHandler(OnStateTransition(
            target_lifecycle_node=node, goal_state='inactive',
            entities=[change(Transition.TRANSITION_ACTIVATE)])),
        RegisterEventHandler(OnStateTransition(
            target_lifecycle_node=node, start_state='configuring', goal_state='unconfigured',
            entities=[OpaqueFunction(function=failed)])),
        change(Transition.TRANSITION_CONFIGURE),
    ]
