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
arm_controller_node in one process over the DDS runtime: it never commands from an old sample.

The samples are handed to the node's own callbacks, stamped in the past or now on the node's
clock; what it publishes is read back by a peer node.
"""
from array import array

import pytest

from bellows_ros import interfaces
from bellows_ros.config.segment import load_segment_params
from bellows_ros.nodes import diagnostics
from bellows_ros.nodes.arm_controller_node import ArmControllerNode, ArmControllerTask
from bellows_ros.runtime import dds_node

MS = 1_000_000  # ns


@pytest.fixture
def controller(monkeypatch):
    monkeypatch.setenv('ROS_DOMAIN_ID', '196')
    dds_node.init([])
    node = ArmControllerNode.on(dds_node)()
    peer = dds_node.Node('peer')
    commands = []
    peer.create_subscription(dds_node.msg.JointState, interfaces.PRESSURE_COMMAND.resolved(),
                             commands.append, interfaces.COMMAND_DEPTH)
    yield node, peer, commands
    dds_node.shutdown()


def feed(node, stamps):
    """
    Hand `node` one held sample of segment 1 per stamp (ns), both halves.

    A stamp of None is the node clock's present: a sample as young as it can be, however slowly a
    loaded machine runs this loop.
    """
    p0 = load_segment_params().p0
    for stamp in stamps:
        stamp = node.get_clock().now().nanoseconds if stamp is None else stamp
        state = dds_node.msg.JointState(name=['segment_1'], position=array('d', [0.1]),
                                        velocity=array('d', [0.0]))
        chambers = dds_node.msg.JointState(name=['segment_1/chain_1', 'segment_1/chain_2'],
                                           effort=array('d', [p0 + 1e5, p0 + 1e5]))
        for half in (state, chambers):
            half.header.stamp.sec, half.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
        node.on_joint_states(state)
        node.on_chambers(chambers)


def test_samples_older_than_max_sample_age_get_no_command_and_say_so(controller):
    node, peer, commands = controller
    task = ArmControllerTask(node)
    max_age = node.get_parameter('max_sample_age').value
    now = node.get_clock().now().nanoseconds
    # A backlog: 100 samples taken 1 s ago, 1 ms apart, handed over now.
    feed(node, [now - 1000 * MS + k * MS for k in range(100)])
    assert node.counts['commands'] == 0
    assert node.counts['stale_skipped'] == 100 // node.control_every
    [status] = task.statuses()
    assert status.level == diagnostics.ERROR, status.message
    assert 'too old to act on' in status.message and '20 skipped' in status.message
    assert float(status.get('sample_age_p50_us')) > 1e6 * max_age

    # Fresh samples are commanded from, and the peer gets those commands.
    feed(node, [None] * 20)
    assert node.counts['commands'] == 20 // node.control_every
    for _ in range(100):
        if len(commands) == node.counts['commands']:
            break
        dds_node.spin_once(peer, timeout_sec=0.05)
    assert len(commands) == node.counts['commands']
    [status] = task.statuses()
    assert status.level != diagnostics.ERROR, status.message
