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
One side of a mixed graph: publishes every topic of the contract with its own values.

It reports when it received the other side's values on every topic.

    BELLOWS_RUNTIME=rclpy|dds python mixed_peer.py SIDE    # SIDE: rclpy or dds (whose values)

Publishes at 10 Hz on every topic in `topics.TOPICS` (the right message type each) and listens on
all of them; prints one JSON line {"complete": true, ...} as soon as every topic brought a message
carrying the other side's values, and runs until SIGINT/SIGTERM.
"""
import json
import sys

from bellows_ros.interfaces import by_name
from bellows_ros.runtime import Node, run

TOPICS = by_name()

# Each side's distinctive values: a tag (names, frame ids) and a number.
SIDES = {'rclpy': ('from_rclpy', 1.25, 11), 'dds': ('from_dds', 2.5, 22)}


def build(msg, ros_type, side):
    """Build the message `side` publishes on a topic of `ros_type`."""
    tag, number, seconds = SIDES[side]
    kind = ros_type.rsplit('/', 1)[1]
    if kind == 'JointState':
        return msg.JointState(header=msg.Header(frame_id=tag), name=[tag, 'x'],
                              position=[number, -number], effort=[number * 2, 0.0])
    if kind == 'WrenchStamped':
        return msg.WrenchStamped(header=msg.Header(frame_id=tag), wrench=msg.Wrench(
            force=msg.Vector3(z=number), torque=msg.Vector3(z=-number)))
    if kind == 'Float64':
        return msg.Float64(data=number)
    if kind == 'DiagnosticArray':
        return msg.DiagnosticArray(header=msg.Header(frame_id=tag), status=[msg.DiagnosticStatus(
            name=tag, message=str(number), values=[msg.KeyValue(key='side', value=tag)])])
    if kind == 'Bool':
        return msg.Bool(data=tag == 'from_dds')
    if kind == 'Clock':
        return msg.Clock(clock=msg.Time(sec=seconds, nanosec=int(number * 1000)))
    if kind == 'JointTrajectory':
        point = msg.JointTrajectoryPoint(positions=[number, -number], velocities=[0.0, number],
                                         time_from_start=msg.Duration(sec=seconds, nanosec=5))
        return msg.JointTrajectory(header=msg.Header(frame_id=tag), joint_names=[tag, 'x'],
                                   points=[point])
    if kind == 'JointTrajectoryControllerState':
        return msg.JointTrajectoryControllerState(
            header=msg.Header(frame_id=tag), joint_names=[tag],
            reference=msg.JointTrajectoryPoint(positions=[number]),
            output=msg.JointTrajectoryPoint(effort=[-number]), speed_scaling_factor=number)
    raise ValueError(ros_type)


def signature(message):
    """Return what distinguishes one side's message from the other's, as plain values."""
    fields = []
    for path in ('header.frame_id', 'name', 'position', 'effort', 'wrench.force.z',
                 'wrench.torque.z', 'data', 'clock.sec', 'clock.nanosec', 'joint_names',
                 'reference.positions', 'output.effort', 'speed_scaling_factor'):
        value = message
        for part in path.split('.'):
            value = getattr(value, part, None)
        if value is not None:
            fields.append(list(value) if not isinstance(value, (str, int, float)) else value)
    for point in getattr(message, 'points', []):
        fields.append([list(point.positions), list(point.velocities),
                       point.time_from_start.sec, point.time_from_start.nanosec])
    for status in getattr(message, 'status', []):
        fields.append([status.name, status.message, [(v.key, v.value) for v in status.values]])
    return fields


class Peer(Node):
    """Publishes its side's values, checks the other side's."""

    def __init__(self, **kwargs):
        self.side = sys.argv[1]
        super().__init__(f'mixed_{self.side}', **kwargs)
        other = next(side for side in SIDES if side != self.side)
        self.received, self.complete = {}, False
        self.outgoing = []
        for topic, ros_type in TOPICS.items():
            kind = getattr(self.msg, ros_type.rsplit('/', 1)[1])
            expected = signature(build(self.msg, ros_type, other))
            self.create_subscription(kind, topic, self.on_message(topic, expected), 10)
            self.outgoing.append((self.create_publisher(kind, topic, 10),
                                  build(self.msg, ros_type, self.side)))
        self.create_timer(0.1, self.publish)

    def on_message(self, topic, expected):
        def callback(message):
            if signature(message) == expected and topic not in self.received:
                self.received[topic] = signature(message)
                if len(self.received) == len(TOPICS) and not self.complete:
                    self.complete = True
                    print(json.dumps({'complete': True, 'node': self.get_name(),
                                      'received': self.received}), flush=True)
        return callback

    def publish(self):
        for publisher, message in self.outgoing:
            publisher.publish(message)


if __name__ == '__main__':
    sys.exit(run(Peer, sys.argv))
