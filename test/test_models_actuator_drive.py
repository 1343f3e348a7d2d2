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
The actuator's drive train (models/actuator_drive.py): encoder scale and no-load chamber speed.

Paper B, section II-A: a 12 V DC gear motor (100:1) turning a 20 TPI lead screw, an encoder on the
motor shaft. Units SI: m per count, m/s of chamber travel.
"""
import dataclasses
import math

import pytest

from bellows_ros.config.hardware import load_drive
from bellows_ros.models.actuator_drive import Drive

DRIVE = load_drive()


def motor(**changes):
    values = {'supply_voltage': 12.0, 'resistance': 2.0, 'inductance': 1e-3,
              'torque_constant': 0.01, 'rotor_inertia': 1e-6, 'viscous_friction': 0.0,
              'gear_ratio': 100.0, 'counts_per_rev': 64, 'lead': 1.27e-3, 'efficiency': 0.35}
    values.update(changes)
    return Drive(**values)


def test_an_encoder_count_is_one_lead_over_the_gear_ratio_and_counts():
    # the default: 1.27 mm per lead-screw turn, 100 motor turns per screw turn, 64 counts per turn
    assert DRIVE.metres_per_count == pytest.approx(1.27e-3 / (100 * 64), rel=1e-12)
    assert motor(counts_per_rev=12).metres_per_count == pytest.approx(1.0583333e-6, rel=1e-7)


def test_without_friction_the_motor_runs_at_supply_over_back_emf():
    # no load, no friction: no current at steady state, so k ω = V
    drive = motor()
    omega = 12.0 / 0.01  # rad/s
    assert drive.max_speed == pytest.approx(omega / (2 * math.pi) / 100 * 1.27e-3, rel=1e-12)


@pytest.mark.parametrize('drive', [DRIVE, motor(viscous_friction=5e-6)], ids=['default', 'lossy'])
def test_max_speed_is_where_motor_torque_meets_viscous_friction(drive):
    # i = (V - k ω) / R and k i = b ω at the no-load steady state (motor side)
    omega = drive.max_speed / drive.lead * 2 * math.pi * drive.gear_ratio
    current = (drive.supply_voltage - drive.torque_constant * omega) / drive.resistance
    assert drive.torque_constant * current == pytest.approx(drive.viscous_friction * omega,
                                                            rel=1e-9, abs=1e-15)
    assert 0 < current and 0 < omega < drive.supply_voltage / drive.torque_constant


def test_speed_grows_with_voltage_and_lead_and_falls_with_friction_and_gearing():
    base = motor(viscous_friction=1e-6).max_speed
    assert motor(viscous_friction=1e-6, supply_voltage=24.0).max_speed == \
        pytest.approx(2 * base, rel=1e-12)
    assert motor(viscous_friction=1e-6, lead=2.54e-3).max_speed == \
        pytest.approx(2 * base, rel=1e-12)
    assert motor(viscous_friction=1e-6, gear_ratio=200.0).max_speed == \
        pytest.approx(base / 2, rel=1e-12)
    assert motor(viscous_friction=1e-5).max_speed < base
    # the default drive: a few mm/s of chamber travel (a unit slip would be orders off)
    assert 1e-3 < DRIVE.max_speed < 1e-2


def test_a_drive_is_a_value():
    with pytest.raises(dataclasses.FrozenInstanceError):
        DRIVE.lead = 2e-3
    assert load_drive() == DRIVE
