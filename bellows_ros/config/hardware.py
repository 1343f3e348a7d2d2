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
The drivers' configuration: config/hardware.yaml -> `ActuatorBoardConfig`, `ArmBusConfig`.

Built without any physics object (no `ActuatorParams`, no `SegmentParams`, no gas law). The drive
train (`hardware.actuator_board.drive`: motor, gearbox, lead screw, encoder) lives here and gives
the encoder scale (`Drive.metres_per_count`); the simulated actuator reads its drive from here too
(`load_drive`). Two limits belong to the physics, which needs them as much, and are read from
their one home as plain keys: the chamber's travel (`actuator.air_chamber.x_min/x_max` of
config/actuator.yaml) and the set-point range (`segment.p0`, `segment.p_max` of
config/segment.yaml).
"""
import dataclasses

from bellows_ros.config import ranges
from bellows_ros.errors import ParameterError
from bellows_ros.interfaces import COMMAND_WATCHDOG
from bellows_ros.io import params as param_files
from bellows_ros.models.actuator_drive import Drive

HARDWARE_SOURCE = 'config/hardware.yaml'


@dataclasses.dataclass(frozen=True)
class ActuatorBoardConfig:
    """
    The actuator board's driver: `hardware.actuator_board.*` and the values it shares, SI units.

    port, baud; stale_timeout, reconnect_interval, heartbeat_period, command_timeout s; duty_max;
    metres_per_count m (encoder scale); x_c_min, x_c_max m (soft end stops, `end_stop_margin`
    inside the chamber's travel).
    """

    port: str
    baud: int
    stale_timeout: float
    reconnect_interval: float
    heartbeat_period: float
    command_timeout: float
    duty_max: float
    metres_per_count: float
    x_c_min: float
    x_c_max: float


@dataclasses.dataclass(frozen=True)
class ArmBusConfig:
    """
    The arm's CAN driver: `hardware.arm_bus.*` and the set-point range, SI units.

    interface, channel, bitrate bit/s, dbc ('' = config/arm.dbc), n_segments; pressure_min,
    pressure_max Pa abs (the segment's p0 and p_max); stale_timeout, command_timeout s.
    """

    interface: str
    channel: str
    bitrate: int
    dbc: str
    n_segments: int
    pressure_min: float
    pressure_max: float
    stale_timeout: float
    command_timeout: float


def _number(flat, name, source):
    value = flat.get(name)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"{source}: parameter '{name}' must be a number, got {value!r}")
    return value


def drive_from_flat(values, source='parameters'):
    """
    Build `Drive` from the names below `hardware.actuator_board.drive.`; refuse unusable values.

    Without the checks a zero gear ratio or count divides by zero in the encoder scale.
    """
    def fail(name, why):
        raise ParameterError(f"{source}: parameter 'hardware.actuator_board.drive.{name}' {why}")
    for name in ('supply_voltage', 'resistance', 'torque_constant', 'rotor_inertia', 'gear_ratio',
                 'counts_per_rev', 'lead', 'efficiency'):
        if name in values and not _number(values, name, source) > 0:
            fail(name, 'must be > 0')
    for name in ('inductance', 'viscous_friction'):
        if name in values and _number(values, name, source) < 0:
            fail(name, 'must be >= 0')
    counts = values.get('counts_per_rev')
    if isinstance(counts, float) and counts != int(counts):
        fail('counts_per_rev', f'must be a whole number, got {counts!r}')
    return param_files.build(Drive, values, f'{source}: hardware.actuator_board.drive')


def load_drive(params_path=None):
    """Return the actuator's `Drive` of config/hardware.yaml with the user's file laid over it."""
    flat = ranges.load('hardware', params_path)
    return drive_from_flat(param_files.section(flat, 'hardware.actuator_board.drive'),
                           params_path or HARDWARE_SOURCE)


def actuator_board_config(params_path=None, actuator_params_path=None):
    """
    `ActuatorBoardConfig` from config/hardware.yaml with the user's file laid over it.

    The encoder scale comes from the drive train (`hardware.actuator_board.drive`). The end stops
    are not repeated in hardware.yaml: they are the chamber's travel of config/actuator.yaml (or
    `actuator_params_path` over it), their one source, and the soft end stops lie
    `end_stop_margin` (m) inside them.
    """
    flat = param_files.section(ranges.load('hardware', params_path),
                               'hardware.actuator_board')
    source = params_path or HARDWARE_SOURCE
    drive = drive_from_flat(param_files.section(flat, 'drive'), source)
    flat = {name: value for name, value in flat.items() if not name.startswith('drive.')}
    actuator = ranges.load('actuator', actuator_params_path)
    actuator_source = actuator_params_path or 'config/actuator.yaml'
    x_min, x_max = (_number(actuator, f'actuator.air_chamber.{end}', actuator_source)
                    for end in ('x_min', 'x_max'))
    margin = _number(flat, 'end_stop_margin', source)
    del flat['end_stop_margin']
    if not x_min + margin < x_max - margin:
        raise ParameterError(f"{source}: parameter 'hardware.actuator_board.end_stop_margin' "
                             f'leaves no travel between the end stops ({x_min:g}, {x_max:g} m)')
    flat.update(metres_per_count=drive.metres_per_count, x_c_min=x_min + margin,
                x_c_max=x_max - margin)
    return param_files.build(ActuatorBoardConfig, flat, source)


def arm_bus_config(params_path=None, segment_params_path=None):
    """
    `ArmBusConfig` from config/hardware.yaml with the user's file laid over it.

    The set-point limits are the segment's ambient pressure p0 and p_max (config/segment.yaml, or
    `segment_params_path` over it): the valves exhaust to ambient, and above p_max the model's
    scaled pressure leaves [0, 1].
    """
    flat = param_files.section(ranges.load('hardware', params_path), 'hardware.arm_bus')
    segment = ranges.load('segment', segment_params_path)
    segment_source = segment_params_path or 'config/segment.yaml'
    p0, p_max = (_number(segment, f'segment.{name}', segment_source) for name in ('p0', 'p_max'))
    if not p_max > p0 > 0:
        raise ParameterError(f"{segment_source}: parameter 'segment.p_max' must exceed p0 > 0")
    flat.update(pressure_min=float(p0), pressure_max=float(p_max))
    config = param_files.build(ArmBusConfig, flat, params_path or HARDWARE_SOURCE)
    if not config.command_timeout >= COMMAND_WATCHDOG:
        # A controller keeps to the contract's watchdog, not to this file: a shorter timeout
        # would vent the arm between two of its commands.
        raise ParameterError(f'{params_path or HARDWARE_SOURCE}: parameter '
                             f"'hardware.arm_bus.command_timeout' = {config.command_timeout:g} s "
                             f'is shorter than the command watchdog of the interface contract '
                             f'({COMMAND_WATCHDOG:g} s, bellows_ros/interfaces.py)')
    return config


def vent_pressure(segment_params_path=None):
    """Pressure that vented chambers hold, Pa abs: the segment's ambient p0 (segment.yaml)."""
    segment = ranges.load('segment', segment_params_path)
    return float(_number(segment, 'segment.p0', segment_params_path or 'config/segment.yaml'))
