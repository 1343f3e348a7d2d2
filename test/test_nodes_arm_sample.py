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
Reading an arm sample message (nodes/arm_sample.py): (Ψ, Ψ̇, p1, p2) per segment, or None.

The messages are the driver's (`probe.arm_sample`, docs/interfaces.md), read back as a sample
subscription hands them over; a message the reader must reject is made from a good one.
"""
import dataclasses
import math

import probe
import pytest

from bellows_ros.nodes.arm_sample import ArmSampleReader

P_LIMIT = 7.5e5  # Pa abs
STAMP = 1_700_000_000_000_000_000  # ns


def sample(psi=(0.1, -0.2), psi_dot=(0.5, -1.5), pressures=(2.0e5, 3.0e5, 1.5e5, 4.0e5),
           segments=(1, 2)):
    """Return an arm sample of `segments` as a sample subscription hands it over."""
    return probe.as_received(probe.arm_sample(STAMP, list(psi), list(psi_dot), list(pressures),
                                              segments=segments))


def test_each_segment_reads_its_angle_rate_and_chain_pressures_by_name():
    rows = ArmSampleReader([1, 2], P_LIMIT).rows(sample())
    assert rows == [(0.1, 0.5, 2.0e5, 3.0e5), (-0.2, -1.5, 1.5e5, 4.0e5)]


def test_the_segments_asked_for_are_read_whatever_the_message_holds_besides_and_its_order():
    message = sample(psi=(0.1, -0.2, 0.3), psi_dot=(1.0, 2.0, 3.0),
                     pressures=(2e5, 3e5, 4e5, 5e5, 6e5, 7e5), segments=(1, 2, 3))
    # the same entries in reverse order: found by name, not by place
    order = list(reversed(range(len(message.name))))
    shuffled = dataclasses.replace(
        message, name=tuple(message.name[k] for k in order),
        position=tuple(message.position[k] for k in order),
        velocity=tuple(message.velocity[k] for k in order),
        effort=tuple(message.effort[k] for k in order))
    reader = ArmSampleReader([3, 1], P_LIMIT)
    assert reader.rows(message) == reader.rows(shuffled) == [(0.3, 3.0, 6e5, 7e5),
                                                             (0.1, 1.0, 2e5, 3e5)]


def test_a_message_without_rates_reads_a_rate_of_zero():
    # a driver without a rate estimate sends an empty velocity array
    rows = ArmSampleReader([1], P_LIMIT).rows(dataclasses.replace(
        sample(psi=(0.2,), psi_dot=(9.0,), pressures=(2e5, 3e5), segments=(1,)), velocity=()))
    assert rows == [(0.2, 0.0, 2e5, 3e5)]


def test_a_message_lacking_a_segment_is_rejected():
    assert ArmSampleReader([1, 3], P_LIMIT).rows(sample()) is None


@pytest.mark.parametrize('field, index, value', [
    ('position', 0, math.nan),        # Ψ of segment 1
    ('velocity', 1, math.inf),        # Ψ̇ of segment 2
    ('effort', 3, math.nan),          # segment 1, chain 2
    ('effort', 4, -1.0),              # a negative absolute pressure
    ('effort', 5, P_LIMIT + 1.0),     # above the limit
])
def test_a_non_finite_value_or_a_pressure_outside_the_range_is_rejected(field, index, value):
    message = sample()
    values = list(getattr(message, field))
    values[index] = value
    assert ArmSampleReader([1, 2], P_LIMIT).rows(
        dataclasses.replace(message, **{field: tuple(values)})) is None


def test_pressures_at_the_ends_of_the_range_are_taken():
    rows = ArmSampleReader([1], P_LIMIT).rows(
        sample(psi=(0.0,), psi_dot=(0.0,), pressures=(0.0, P_LIMIT), segments=(1,)))
    assert rows == [(0.0, 0.0, 0.0, P_LIMIT)]


def test_arrays_shorter_than_the_names_are_a_malformed_message():
    message = sample()
    assert ArmSampleReader([1, 2], P_LIMIT).rows(
        dataclasses.replace(message, effort=message.effort[:4])) is None
