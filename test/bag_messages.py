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
Bags the tests write with rosbags (no ROS): device samples, stamped, in each format bag.py reads.

A layout is where a device group's sample goes:
- 'sample' (the contract now, interfaces.py): one message per sample, the chambers' pressures and
  the actuator's spring force in it;
- 'split' (recorded before): the pressures on a chambers topic of their own (`/bellows/chambers`,
  `/actuator/chambers`), the actuator's force on `/bellows/wrench` (frame_id `actuator`);
- 'shared' (the actuator only, before it had topics of its own): its samples on the arm's
  `/joint_states` and `/bellows/chambers`.
A value given as None is one the sample lacks: NaN in a sample message, no message on a topic of
its own. The arm's tau_ext is on `/bellows/wrench` (frame_id `segment_1`) in every layout.
"""
import math

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores

from bellows_ros import interfaces

STORE = get_typestore(Stores.ROS2_JAZZY)
JOINT_STATE = 'sensor_msgs/msg/JointState'
WRENCH = 'geometry_msgs/msg/WrenchStamped'
ACTUATOR_LAYOUTS = ('sample', 'split', 'shared')
ARM_LAYOUTS = ('sample', 'split')
# The older layouts' (joint states, chambers) topics of the actuator.
ACTUATOR_OLDER_TOPICS = {'split': ('/actuator/joint_states', '/actuator/chambers'),
                         'shared': ('/joint_states', '/bellows/chambers')}
NAN = math.nan


def header(ns, frame=''):
    """std_msgs/Header stamped `ns` nanoseconds."""
    stamp = STORE.types['builtin_interfaces/msg/Time'](sec=ns // 10 ** 9, nanosec=ns % 10 ** 9)
    return STORE.types['std_msgs/msg/Header'](stamp=stamp, frame_id=frame)


def joints(ns, names, position=(), effort=(), velocity=()):
    """sensor_msgs/JointState of `names` with `position`, `velocity` and `effort`, stamped `ns`."""
    return STORE.types[JOINT_STATE](header=header(ns), name=list(names),
                                    position=np.array(position, float),
                                    velocity=np.array(velocity, float),
                                    effort=np.array(effort, float))


def wrench(ns, force_z=0.0, frame='actuator', torque_z=0.0):
    """geometry_msgs/WrenchStamped of `frame` with force.z and torque.z, stamped `ns`."""
    vector = STORE.types['geometry_msgs/msg/Vector3']
    body = STORE.types['geometry_msgs/msg/Wrench'](force=vector(x=0.0, y=0.0, z=force_z),
                                                   torque=vector(x=0.0, y=0.0, z=torque_z))
    return STORE.types[WRENCH](header=header(ns, frame), wrench=body)


def _or_nan(value):
    return NAN if value is None else value


def actuator_messages(ns, x_c, x_s, p, f, layout='sample'):
    """[(topic, message)] of one actuator sample in `layout`."""
    if layout == 'sample':
        return [('/actuator/joint_states',
                 joints(ns, interfaces.actuator_sample_names(), position=(x_c, x_s, NAN),
                        effort=(NAN, _or_nan(f), _or_nan(p))))]
    joint_topic, chamber_topic = ACTUATOR_OLDER_TOPICS[layout]
    messages = [(joint_topic, joints(ns, interfaces.ACTUATOR_JOINTS, position=(x_c, x_s)))]
    if p is not None:
        messages.append((chamber_topic, joints(ns, [interfaces.ACTUATOR_CHAMBER], effort=(p,))))
    if f is not None:
        messages.append(('/bellows/wrench', wrench(ns, f)))
    return messages


def arm_messages(ns, psi, psi_dot, p1, p2, tau_ext, layout='sample'):
    """[(topic, message)] of one sample of segment_1 in `layout` ('sample' or 'split')."""
    if layout == 'sample':
        messages = [('/joint_states',
                     joints(ns, interfaces.arm_sample_names([1]), position=(psi, NAN, NAN),
                            velocity=(psi_dot, NAN, NAN),
                            effort=(NAN, _or_nan(p1), _or_nan(p2))))]
    else:
        messages = [('/joint_states', joints(ns, ['segment_1'], position=(psi,),
                                             velocity=(psi_dot,)))]
        if p1 is not None and p2 is not None:
            messages.append(('/bellows/chambers',
                             joints(ns, ['segment_1/chain_1', 'segment_1/chain_2'],
                                    effort=(p1, p2))))
    if tau_ext is not None:
        messages.append(('/bellows/wrench', wrench(ns, frame='segment_1', torque_z=tau_ext)))
    return messages


def write_bag(path, samples, storage=StoragePlugin.SQLITE3, version=8, log_time=None):
    """
    Write `samples` (each a list of (topic, message)) as a new bag `path`; return `path`.

    A message is logged at `log_time(sample index, its stamp ns)`, by default its stamp.
    """
    with Writer(path, version=version, storage_plugin=storage) as writer:
        connections = {}
        for k, messages in enumerate(samples):
            for topic, message in messages:
                kind = message.__msgtype__
                if topic not in connections:
                    connections[topic] = writer.add_connection(topic, kind, typestore=STORE)
                stamp = message.header.stamp
                ns = stamp.sec * 10 ** 9 + stamp.nanosec
                writer.write(connections[topic], ns if log_time is None else log_time(k, ns),
                             STORE.serialize_cdr(message, kind))
    return path


def write_actuator_bag(path, rows, storage=StoragePlugin.SQLITE3, layout='sample', **options):
    """rows: (stamp ns, x_c, x_s, p, f) each -> a bag of the actuator's samples in `layout`."""
    return write_bag(path, [actuator_messages(*row, layout=layout) for row in rows], storage,
                     **options)


def write_arm_bag(path, rows, storage=StoragePlugin.SQLITE3, layout='sample', **options):
    """rows: (stamp ns, psi, psi_dot, p1, p2, tau_ext) each -> a bag of segment_1's samples."""
    return write_bag(path, [arm_messages(*row, layout=layout) for row in rows], storage,
                     **options)
