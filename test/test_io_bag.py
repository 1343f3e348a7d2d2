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
rosbag2 recordings as data tables (bellows_ros/io/bag.py).

The bags are written here as `bellows record` writes them: rosbag2 version 9, MCAP, with
rosbags' writer and the ROS 2 Jazzy type store (test/bag_messages.py). A sample's values are
found by name in its own message; the arm's wrench is held onto the samples by stamp.
"""
import math

from bag_messages import arm_messages, joints, wrench, write_arm_bag, write_bag
import numpy as np
import pytest
from rosbags.rosbag2 import StoragePlugin

from bellows_ros.errors import DataError
from bellows_ros.io.bag import read_bag_table

START = 7 * 10 ** 9 + 250  # ns: a stamp with sub-second nanoseconds
STEP = 1_000_000           # ns: 1 kHz
NAN = math.nan


def write_mcap(path, samples):
    return write_bag(path, samples, StoragePlugin.MCAP, version=9)


def arm_rows(n=30):
    """(stamp ns, psi, psi_dot, p1, p2, tau_ext) of segment_1 at 1 kHz."""
    return [(START + k * STEP, 0.2 * math.sin(k / 5), 0.04 * math.cos(k / 5), 2e5 + 100.0 * k,
             1.5e5 - 50.0 * k, 0.01 * k - 0.1) for k in range(n)]


def test_an_arm_recording_reads_back_exactly_what_was_written(tmp_path):
    rows = arm_rows()
    write_arm_bag(tmp_path / 'bag', rows, StoragePlugin.MCAP, version=9)
    table = read_bag_table(tmp_path / 'bag', 'segment')
    assert table.names == ['t', 'psi', 'p1', 'p2', 'tau_ext', 'psi_dot']
    assert table.path == str(tmp_path / 'bag') and table.lines is None  # a bag has no lines
    # t: seconds from the first sample's stamp.
    np.testing.assert_allclose(table['t'], np.arange(len(rows)) * 1e-3, rtol=0, atol=1e-12)
    for i, name in enumerate(('psi', 'psi_dot', 'p1', 'p2', 'tau_ext'), start=1):
        np.testing.assert_array_equal(table[name], [row[i] for row in rows], err_msg=name)
    # Every column from another channel than the sample's joints is marked as aligned.
    assert set(table.held) == {'p1', 'p2', 'tau_ext'}
    assert all(np.all(age == 0.0) for _, age, _ in table.held.values())


def test_the_wrench_is_held_onto_the_samples_by_stamp(tmp_path):
    # The wrench comes at half the rate, half a step late, from the third sample on; a wrench of
    # another frame (segment_2's) comes between, and counts for nothing.
    samples = []
    for k in range(20):
        ns = START + k * STEP
        sample = arm_messages(ns, 0.01 * k, 0.0, 2e5, 1.5e5, None)
        if k % 2 == 0 and k >= 2:
            sample.append(('/bellows/wrench', wrench(ns + STEP // 2, frame='segment_1',
                                                     torque_z=float(k))))
            sample.append(('/bellows/wrench', wrench(ns + STEP // 2, frame='segment_2',
                                                     torque_z=-99.0)))
        samples.append(sample)
    write_mcap(tmp_path / 'bag', samples)
    table = read_bag_table(tmp_path / 'bag', 'segment')
    # Row k takes the latest wrench stamped at or before it; rows before any take the first.
    expected = [2.0 if k < 3 else float(k - 1 if k % 2 else k - 2) for k in range(20)]
    np.testing.assert_array_equal(table['tau_ext'], expected)
    channel, age, step = table.held['tau_ext']
    assert channel == '/bellows/wrench' and step == pytest.approx(2e-3)  # the wrench's own step
    np.testing.assert_allclose(age[:4], [2.5e-3, 1.5e-3, 0.5e-3, 0.5e-3], atol=1e-12)


def test_a_samples_values_are_found_by_name_whatever_the_order(tmp_path):
    names = ['segment_1/chain_2', 'segment_2', 'segment_1', 'segment_1/chain_1']
    samples = [[('/joint_states', joints(ns, names, position=(NAN, 9.0, 0.1 * k, NAN),
                                         velocity=(NAN, 9.0, 0.5, NAN),
                                         effort=(1.5e5, NAN, NAN, 2e5 + k))),
                ('/joint_states', joints(ns + 1, ['segment_2'], position=(7.0,),
                                         velocity=(7.0,))),    # another segment's: skipped
                ('/bellows/wrench', wrench(ns, frame='segment_1'))]
               for k, ns in enumerate(range(START, START + 10 * STEP, STEP))]
    write_mcap(tmp_path / 'bag', samples)
    table = read_bag_table(tmp_path / 'bag', 'segment')
    assert len(table) == 10
    np.testing.assert_allclose(table['psi'], 0.1 * np.arange(10))
    np.testing.assert_array_equal(table['psi_dot'], 0.5)
    np.testing.assert_array_equal(table['p1'], 2e5 + np.arange(10))
    np.testing.assert_array_equal(table['p2'], 1.5e5)


def test_a_joint_without_the_wanted_field_is_named_with_its_stamp(tmp_path):
    samples = [[('/joint_states', joints(START, ['segment_1'], position=(0.1,)))]]  # no velocity
    write_mcap(tmp_path / 'bag', samples)
    with pytest.raises(DataError) as error:
        read_bag_table(tmp_path / 'bag', 'segment')
    assert str(error.value) == (f"{tmp_path / 'bag'}: /joint_states: joint 'segment_1' has no "
                                f'velocity (stamp {START} ns)')


def test_a_bag_without_the_systems_samples_or_an_unknown_system_is_refused(tmp_path):
    bag = write_arm_bag(tmp_path / 'bag', arm_rows(5), StoragePlugin.MCAP, version=9)
    with pytest.raises(DataError, match=r"bag: unknown system 'arm' \(segment or actuator\)"):
        read_bag_table(bag, 'arm')
    # An arm's bag read as the actuator's: none of its messages names the actuator's joints.
    with pytest.raises(DataError, match='no messages on /actuator/joint_states .*with joint'
                                        r'\(s\) air_chamber, spring'):
        read_bag_table(bag, 'actuator')


def test_metadata_that_is_no_file_is_named(tmp_path):
    bag = tmp_path / 'bag'
    (bag / 'metadata.yaml').mkdir(parents=True)
    with pytest.raises(DataError, match='bag/metadata.yaml: not a regular file'):
        read_bag_table(bag, 'segment')
