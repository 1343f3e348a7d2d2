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
The model node's `model_health` (#21 point 4): the generalised `ModelHealth` on segment rows.

The data come from `SegmentPlant` (the simulated arm's segment, free, its chains' pressures
swept slowly so the arm bends back and forth short of its end stops) and the model node's own
computation: `SegmentModel` on the measured Ψ, p1, p2 and Ψ̇ differenced from the measured Ψ (as
the driver does: no velocity on the bus), and τ_ext (2) with Ψ̈ from successive Ψ̇. The arm has
no torque sensor: the code under test gets τ_ext per segment, as the node's ring
buffer holds it. A load torque on the second segment is switched on mid-run. Its size: the
differenced Ψ̇ flips the sign of the model's friction term (5) from sample to sample, so τ_ext's
noise is about c_f + c_f,p p̄ (0.6 N·m here), and the default, quasi-static model leaves out the
plant's damping and inertia, part of the healthy residual while the arm swings; the limit is
about 3 floors, 1.9 N·m.
"""
import math

import numpy as np
import pytest

from bellows_ros.config.segment import load_segment
from bellows_ros.doctor import live
from bellows_ros.models.derivatives import rate
from bellows_ros.models.segment import external_torque, SegmentModel
from bellows_ros.models.segment_plant import SegmentPlant

PARAMS, PLANT, _ = load_segment()
DT = 1e-3
NAMES = ('segment_1', 'segment_2')
T_FAULT = 30.0
LOAD = 2.5              # N·m on the segment from T_FAULT


def arm_run(seconds, fault=None, seed=1, swing=2.0e4):
    """Return rows (t, τ_ext of each of NAMES); `fault` ('load') hits NAMES[1] from T_FAULT."""
    plants = [SegmentPlant(PARAMS, PLANT, seed=seed + i) for i in range(len(NAMES))]
    models = [SegmentModel(PARAMS) for _ in NAMES]
    previous, psi_ddot = [None] * len(NAMES), [0.0] * len(NAMES)
    last_psi, psi_dot = [None] * len(NAMES), [0.0] * len(NAMES)
    rows = []
    for k in range(int(round(seconds / DT))):
        t = k * DT
        faulty = fault is not None and t >= T_FAULT
        row = [t]
        for i, (plant, model) in enumerate(zip(plants, models)):
            dp = swing * math.sin(2 * math.pi * t / 12.0 + i)    # Pa
            load = LOAD if fault == 'load' and faulty and i == 1 else 0.0
            s = plant.step(DT, 2.0e5 + dp, 2.0e5 - dp, tau_load=load)
            psi_dot[i] = rate(s.psi, last_psi[i], DT, psi_dot[i])     # the driver's Ψ̇
            last_psi[i] = s.psi
            drive = model.step(s.psi, psi_dot[i], s.p1, s.p2).tau_drive
            psi_ddot[i] = rate(psi_dot[i], previous[i], DT, psi_ddot[i])
            previous[i] = psi_dot[i]
            row.append(float(external_torque(PARAMS, s.psi, psi_dot[i], psi_ddot[i], drive)))
        rows.append(row)
    return np.array(rows)


@pytest.fixture(scope='module')
def healthy():
    return arm_run(45.0)


def feed(health, data, every=1000):
    """Feed `data` in 1 s chunks, as the node's ring buffer gives them; return the states."""
    states = []
    for start in range(0, len(data), every):
        chunk = data[start:start + every]
        states.append((chunk[-1, 0], health.update(dict(zip(('t', *NAMES), chunk.T)))))
    return states


def test_a_healthy_arm_stays_within_the_floor(healthy):
    health = live.segment_health(NAMES, calibration=20.0, window=5.0)
    states = feed(health, healthy)
    assert {s for t, s in states if t < 19.0} == {'calibrating'}
    assert {s for t, s in states if t > 21.0} == {'healthy'}, states
    values = health.values()
    still = arm_run(3.0, swing=0.0)[1000:]         # the arm at rest, its chains settled
    for k, name in enumerate(NAMES):
        # The floor comes from the data: the noise of τ_ext (the sensors' through the model),
        # as its spread on the arm at rest shows; the swing does not raise it.
        noise = float(np.std(still[:, 1 + k]))
        assert 0.75 < values[f'noise_floor_{name}'] / noise < 1.25, (values, noise)
        assert values[f'ratio_{name}'] < values[f'limit_{name}'], values
        assert values[f'limit_{name}'] >= live.LIMIT_MIN
    print({k: round(v, 4) for k, v in values.items() if not isinstance(v, str)})


def test_a_load_switched_on_leaves_the_floor_on_its_segment():
    health = live.segment_health(NAMES, calibration=20.0, window=5.0)
    states = feed(health, arm_run(45.0, fault='load'))
    out = [t for t, s in states if s == 'out of floor']
    assert out and all(t > T_FAULT for t in out), states
    assert out[0] - T_FAULT < 10.0, states     # sample time, not wall-clock
    values = health.values()
    first, second = NAMES
    assert values[f'ratio_{second}'] > values[f'limit_{second}'], values
    assert values[f'ratio_{first}'] < values[f'limit_{first}'], values   # the other is fine
    print('load', {k: round(v, 4) for k, v in values.items() if not isinstance(v, str)})


def test_a_noise_free_column_gets_a_finite_floor():
    t = np.arange(0.0, 1.0, DT)
    floors = live.local_floors(NAMES, {'t': t, NAMES[0]: np.sin(t), NAMES[1]: 0 * t})
    assert 0.0 < floors[NAMES[1]] < floors[NAMES[0]] and all(map(math.isfinite, floors.values()))
