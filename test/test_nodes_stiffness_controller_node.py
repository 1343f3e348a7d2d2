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
stiffness_controller_node in the test's process: set-points and samples in, motor duties out.

The node is built in an rclpy context of the test's own (on a domain of its own); samples are
handed to its sample callback as its sample subscription hands them over, set-points to its
set-point callback, and its two publishers are replaced by lists, so every message it sends is
seen in order. Its loop on the simulated actuator is test_graph_stiffness.py's.
"""
import math

import pytest

from bellows_ros import interfaces
from bellows_ros.errors import ParameterError
from bellows_ros.nodes import diagnostics
from bellows_ros.nodes.stiffness_controller_node import StiffnessControllerNode
from bellows_ros.runtime.joint_state_cdr import JointStateSample
from bellows_ros.runtime.messages import msg

NAMES = interfaces.actuator_sample_names()
MS = 1_000_000  # ns
X_S, FORCE = 0.004, 6.0  # m, N: a spring held still


@pytest.fixture
def controller(build_node):
    """Return `build(**parameters)`: the node, its publishers replaced by lists of messages."""
    def build(**parameters):
        node = build_node(StiffnessControllerNode, **parameters)
        node.duties, node.stiffnesses = [], []
        node.motor_pub = Recorder(node.duties)
        node.stiffness_pub = Recorder(node.stiffnesses)
        return node
    return build


class Recorder:
    """A publisher that keeps the data of what it is given."""

    def __init__(self, into):
        self.into = into

    def publish(self, message):
        self.into.append(message.data)


def feed(node, count, x_c, pressure=None, force=FORCE, start=0, names=NAMES):
    """Hand `node` `count` samples 1 ms apart at compression `x_c` (m), pressure in Pa abs."""
    pressure = node.setpoint.params.p_ref if pressure is None else pressure
    for k in range(start, start + count):
        node.on_sample(JointStateSample(1_700_000_000 * 10 ** 9 + k * MS, names,
                                        (x_c, X_S, math.nan), (), (math.nan, force, pressure)))


def control_status(node):
    status = diagnostics.DiagnosticStatusWrapper()
    node.diagnose_control(status)
    return status


@pytest.mark.parametrize('name, value', [('control_every', 0), ('pd.duty_max', 1.5),
                                         ('gas_time_constant', 0.0),
                                         ('model_health.calibration', 1.0)])
def test_a_bad_parameter_is_refused_naming_it(controller, name, value):
    with pytest.raises(ParameterError, match=f"^stiffness_controller_node: parameter '{name}'"):
        controller(**{name: value})


def test_without_a_set_point_it_holds_still_and_reports_the_present_stiffness(controller):
    node = controller(control_every=5, publish_every=2)
    assert control_status(node).level == diagnostics.STALE  # no samples yet
    feed(node, 20, x_c=0.0)
    # one duty per 5 samples, one stiffness per 2 of those
    assert node.duties == [0.0] * 4 and len(node.stiffnesses) == 2
    k_low, k_high = node.setpoint.range()
    assert all(k_low <= k <= k_high for k in node.stiffnesses)
    assert node.target is None and control_status(node).level == diagnostics.OK


def test_a_set_point_becomes_a_compression_the_pd_drives_to(controller):
    node = controller(control_every=1, **{'pd.kp': 400.0, 'pd.kd': 0.0})
    node.on_setpoint(msg.Float64(data=2000.0))
    target = node.target
    assert target == pytest.approx(node.setpoint.target())
    x_c = target - 5e-4  # below the target: the motor compresses the chamber
    feed(node, 3, x_c)
    assert node.duties[-1] == pytest.approx(400.0 * (node.target - x_c)) and \
        0.0 < node.duties[-1] < 0.8
    feed(node, 1, x_c=0.0, start=3)  # far off: the duty is limited
    assert node.duties[-1] == 0.8
    assert control_status(node).get('stiffness_setpoint') == '2000.0'


def test_a_set_point_out_of_reach_is_refused_and_the_target_kept(controller):
    node = controller()
    node.on_setpoint(msg.Float64(data=2000.0))
    target = node.target
    k_high = node.setpoint.range()[1]
    node.on_setpoint(msg.Float64(data=k_high * 2))
    assert node.counts['rejected_setpoints'] == 1
    assert node.target == target and node.setpoint.k_target == 2000.0
    node.on_setpoint(msg.Float64(data=2000.0))  # repeated: nothing to do
    assert node.counts['rejected_setpoints'] == 1 and node.target == target


def test_samples_without_pressure_are_not_acted_on_and_without_force_still_are(controller):
    node = controller(control_every=1)
    feed(node, 3, x_c=0.0, pressure=math.nan)
    assert node.duties == [] and node.counts['samples_without_pressure'] == 3
    feed(node, 2, x_c=0.0, force=math.nan, start=3)
    assert node.duties == [0.0, 0.0] and node.counts['samples_without_force'] == 2
    # another publisher's joints on the topic: not this node's samples, nothing counted
    feed(node, 2, x_c=0.0, start=5, names=('joint_a', 'joint_b', 'joint_c'))
    assert len(node.duties) == 2 and node.samples == 2


def test_live_parameters_take_effect_from_the_next_control_step(controller):
    node = controller(control_every=5)
    node.on_setpoint(msg.Float64(data=2000.0))
    feed(node, 10, x_c=0.0)
    assert len(node.duties) == 2
    node.on_parameters({'control_every': 1, 'pd.duty_max': 0.3, 'gas_time_constant': 7.0})
    feed(node, 3, x_c=0.0, start=10)
    assert node.duties[2:] == [0.3] * 3  # every sample, limited to the new duty_max
    assert node.pd.gains.duty_max == 0.3 and node.pd.gains.kp == 400.0  # the rest kept
    assert node.setpoint.gas_time_constant == 7.0


def test_an_initial_stiffness_is_held_from_the_first_control_step(controller):
    node = controller(control_every=1, initial_stiffness=2000.0)
    assert node.setpoint.k_target == 2000.0
    feed(node, 1, x_c=0.0)
    assert node.target is not None and node.duties == [0.8]
