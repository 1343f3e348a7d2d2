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
A managed (lifecycle) node: ROS 2's state machine, served the same way on both runtimes.

The states, transitions and labels are rcl_lifecycle's default state machine
(rcl_lifecycle/src/default_state_machine.c, design.ros2.org "Managed nodes"); their ids are the
constants of lifecycle_msgs/msg/State and Transition. A node is brought up from `unconfigured`
by `configure` (-> inactive) and `activate` (-> active); `deactivate`, `cleanup` and `shutdown`
take it back. Each primary transition passes through a transition state whose callback returns
SUCCESS, FAILURE (stay where it was) or ERROR (-> errorprocessing, whose callback decides between
unconfigured and finalized).

`Lifecycle` serves rcl_lifecycle's interface on the node: `~/change_state`, `~/get_state`,
`~/get_available_states`, `~/get_available_transitions`, `~/get_transition_graph` (lifecycle_msgs
services) and `~/transition_event`, so that `ros2 lifecycle` and launch_ros's lifecycle events
reach a node on either runtime. It is this module on both (not rclpy's LifecycleNode on one):
one state machine, one behaviour, tested once from outside with `ros2 lifecycle`.
"""
from typing import Callable, Dict, Iterable, List, NamedTuple, Optional

from bellows_ros.runtime.cdr import TYPESTORE

# Callback results, as rclpy's TransitionCallbackReturn labels them.
SUCCESS, FAILURE, ERROR = 'transition_success', 'transition_failure', 'transition_error'


def _constants(ros_name: str) -> Dict[str, int]:
    return {name: value for name, _type, value in TYPESTORE.fielddefs[ros_name][0]}


STATE = _constants('lifecycle_msgs/msg/State')
TRANSITION = _constants('lifecycle_msgs/msg/Transition')

# State id -> label, primary states then transition states.
STATES = {STATE['PRIMARY_STATE_UNKNOWN']: 'unknown',
          STATE['PRIMARY_STATE_UNCONFIGURED']: 'unconfigured',
          STATE['PRIMARY_STATE_INACTIVE']: 'inactive',
          STATE['PRIMARY_STATE_ACTIVE']: 'active',
          STATE['PRIMARY_STATE_FINALIZED']: 'finalized',
          STATE['TRANSITION_STATE_CONFIGURING']: 'configuring',
          STATE['TRANSITION_STATE_CLEANINGUP']: 'cleaningup',
          STATE['TRANSITION_STATE_SHUTTINGDOWN']: 'shuttingdown',
          STATE['TRANSITION_STATE_ACTIVATING']: 'activating',
          STATE['TRANSITION_STATE_DEACTIVATING']: 'deactivating',
          STATE['TRANSITION_STATE_ERRORPROCESSING']: 'errorprocessing'}
_ID = {label: state_id for state_id, label in STATES.items()}


class Edge(NamedTuple):
    """One transition of the graph: its id and label, from one state to another (labels)."""

    transition_id: int
    label: str
    start: str
    goal: str


# rcl_lifecycle's default graph, in its order of registration: (Transition constant, label,
# start, goal). A failed shutdown still ends in finalized: nothing more can be asked of the node.
_GRAPH = (
    ('CONFIGURE', 'configure', 'unconfigured', 'configuring'),
    ('ON_CONFIGURE_SUCCESS', SUCCESS, 'configuring', 'inactive'),
    ('ON_CONFIGURE_FAILURE', FAILURE, 'configuring', 'unconfigured'),
    ('ON_CONFIGURE_ERROR', ERROR, 'configuring', 'errorprocessing'),
    ('CLEANUP', 'cleanup', 'inactive', 'cleaningup'),
    ('ON_CLEANUP_SUCCESS', SUCCESS, 'cleaningup', 'unconfigured'),
    ('ON_CLEANUP_FAILURE', FAILURE, 'cleaningup', 'inactive'),
    ('ON_CLEANUP_ERROR', ERROR, 'cleaningup', 'errorprocessing'),
    ('ACTIVATE', 'activate', 'inactive', 'activating'),
    ('ON_ACTIVATE_SUCCESS', SUCCESS, 'activating', 'active'),
    ('ON_ACTIVATE_FAILURE', FAILURE, 'activating', 'inactive'),
    ('ON_ACTIVATE_ERROR', ERROR, 'activating', 'errorprocessing'),
    ('DEACTIVATE', 'deactivate', 'active', 'deactivating'),
    ('ON_DEACTIVATE_SUCCESS', SUCCESS, 'deactivating', 'inactive'),
    ('ON_DEACTIVATE_FAILURE', FAILURE, 'deactivating', 'active'),
    ('ON_DEACTIVATE_ERROR', ERROR, 'deactivating', 'errorprocessing'),
    ('UNCONFIGURED_SHUTDOWN', 'shutdown', 'unconfigured', 'shuttingdown'),
    ('INACTIVE_SHUTDOWN', 'shutdown', 'inactive', 'shuttingdown'),
    ('ACTIVE_SHUTDOWN', 'shutdown', 'active', 'shuttingdown'),
    ('ON_SHUTDOWN_SUCCESS', SUCCESS, 'shuttingdown', 'finalized'),
    ('ON_SHUTDOWN_FAILURE', FAILURE, 'shuttingdown', 'finalized'),
    ('ON_SHUTDOWN_ERROR', ERROR, 'shuttingdown', 'errorprocessing'),
    ('ON_ERROR_SUCCESS', SUCCESS, 'errorprocessing', 'unconfigured'),
    ('ON_ERROR_FAILURE', FAILURE, 'errorprocessing', 'finalized'),
    ('ON_ERROR_ERROR', ERROR, 'errorprocessing', 'finalized'),
)
GRAPH = [Edge(TRANSITION[f'TRANSITION_{name}'], label, start, goal)
         for name, label, start, goal in _GRAPH]
# The callback run in each transition state: the managed node's method of that name.
CALLBACKS = {'configuring': 'on_configure', 'cleaningup': 'on_cleanup',
             'activating': 'on_activate', 'deactivating': 'on_deactivate',
             'shuttingdown': 'on_shutdown', 'errorprocessing': 'on_error'}


class StateMachine:
    """
    The default lifecycle state machine, no I/O: `trigger` runs a transition and its callbacks.

    `callbacks` maps a transition state's label to `callback(previous_state_label) -> result`;
    a missing one succeeds, an exception counts as ERROR (as rclpy does), and a result that is
    not SUCCESS, FAILURE or ERROR is an ERROR too. `on_change(edge)` is told every step taken.
    """

    def __init__(self, callbacks: Dict[str, Callable[[str], str]],
                 on_change: Callable[[Edge], None] = lambda edge: None,
                 log_error: Callable[[str], None] = lambda text: None) -> None:
        self.state = 'unconfigured'
        self._callbacks, self._on_change, self._log_error = callbacks, on_change, log_error

    def available(self) -> List[Edge]:
        """Return the transitions that can start from the current state."""
        return [edge for edge in GRAPH if edge.start == self.state]

    def find(self, transition_id: int = 0, label: str = '') -> Optional[Edge]:
        """Return the transition a request names (by label if it has one, as rclpy), or None."""
        for edge in self.available():
            if (edge.label == label) if label else (edge.transition_id == transition_id):
                return edge if edge.label not in (SUCCESS, FAILURE, ERROR) else None
        return None

    def trigger(self, edge: Edge) -> str:
        """Take `edge` from the current state, run its callback(s); returns the result."""
        previous = self.state
        self._step(edge)
        result = self._run(self.state, previous)
        self._step(self._result_edge(result))
        if result == ERROR:
            self._step(self._result_edge(self._run('errorprocessing', previous)))
        return result

    def _run(self, transition_state: str, previous: str) -> str:
        callback = self._callbacks.get(transition_state)
        if callback is None:
            return SUCCESS
        try:
            result = callback(previous)
        except Exception as exc:  # noqa: BLE001 (rclpy's rule: a raising callback is an ERROR)
            self._log_error(f'{CALLBACKS[transition_state]} raised {type(exc).__name__}: {exc}')
            return ERROR
        return result if result in (SUCCESS, FAILURE, ERROR) else ERROR

    def _result_edge(self, result: str) -> Edge:
        edge, = (e for e in self.available() if e.label == result)
        return edge

    def _step(self, edge: Edge) -> None:
        self.state = edge.goal
        self._on_change(edge)


class Lifecycle:
    """
    rcl_lifecycle's services and transition events on a bellows node (either runtime).

    `node` is a runtime.Node whose class defines any of on_configure, on_activate,
    on_deactivate, on_cleanup, on_shutdown, on_error: `method(previous_state) -> SUCCESS |
    FAILURE | ERROR`. `trigger('configure')` drives the node itself (autostart, shutdown on exit).
    """

    def __init__(self, node) -> None:
        self.node = node
        self._event_pub = node.create_publisher(node.msg.TransitionEvent, '~/transition_event',
                                                10)
        callbacks = {state: getattr(node, name) for state, name in CALLBACKS.items()
                     if hasattr(node, name)}
        self.machine = StateMachine(callbacks, self._publish_event,
                                    node.get_logger().error)
        srv = node.srv
        for name, srv_type, callback in (
                ('change_state', srv.ChangeState, self._on_change_state),
                ('get_state', srv.GetState, self._on_get_state),
                ('get_available_states', srv.GetAvailableStates, self._on_get_available_states),
                ('get_available_transitions', srv.GetAvailableTransitions,
                 self._on_get_available_transitions),
                ('get_transition_graph', srv.GetAvailableTransitions,
                 self._on_get_transition_graph)):
            node.create_service(srv_type, f'~/{name}', callback)

    @property
    def state(self) -> str:
        """The current state's label ('unconfigured', 'inactive', 'active', ...)."""
        return self.machine.state

    def trigger(self, label: str) -> str:
        """Run the transition `label` from the current state; FAILURE when it has none."""
        edge = self.machine.find(label=label)
        if edge is None:
            self.node.get_logger().warn(f"lifecycle: no transition '{label}' from "
                                        f'{self.machine.state}')
            return FAILURE
        return self.machine.trigger(edge)

    # --- services --------------------------------------------------------------------------------
    def _on_change_state(self, request, response):
        edge = self.machine.find(request.transition.id, request.transition.label)
        if edge is None:
            self.node.get_logger().warn(
                f'lifecycle: transition {request.transition.label or request.transition.id} '
                f'is not available from {self.machine.state}')
            response.success = False
        else:
            response.success = self.machine.trigger(edge) == SUCCESS
        return response

    def _on_get_state(self, request, response):
        self._fill_state(response.current_state, self.machine.state)
        return response

    def _on_get_available_states(self, request, response):
        response.available_states = [self._state(label) for label in STATES.values()]
        return response

    def _on_get_available_transitions(self, request, response):
        response.available_transitions = self._descriptions(self.machine.available())
        return response

    def _on_get_transition_graph(self, request, response):
        response.available_transitions = self._descriptions(GRAPH)
        return response

    # --- messages --------------------------------------------------------------------------------
    def _class(self, name: str) -> type:
        return self.node.runtime.service_message(f'lifecycle_msgs/msg/{name}')

    def _state(self, label: str):
        state = self._class('State')()
        self._fill_state(state, label)
        return state

    @staticmethod
    def _fill_state(state, label: str) -> None:
        state.id, state.label = _ID[label], label

    def _descriptions(self, edges: Iterable[Edge]) -> list:
        items = []
        for edge in edges:
            item = self._class('TransitionDescription')()
            item.transition.id, item.transition.label = edge.transition_id, edge.label
            self._fill_state(item.start_state, edge.start)
            self._fill_state(item.goal_state, edge.goal)
            items.append(item)
        return items

    def _publish_event(self, edge: Edge) -> None:
        msg = self.node.msg
        event = msg.TransitionEvent()
        event.timestamp = self.node.get_clock().now().nanoseconds
        event.transition.id, event.transition.label = edge.transition_id, edge.label
        self._fill_state(event.start_state, edge.start)
        self._fill_state(event.goal_state, edge.goal)
        self._event_pub.publish(event)
