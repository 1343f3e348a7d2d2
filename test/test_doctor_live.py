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
The doctor live (#21 point 4): rolling residual, trigger, worker, on data of the real plant.

The data come from `ActuatorPlant` with the controller model's standing physics (wall bulging,
buckling) and a leak switched on mid-run (`set_strengths`); the code under test gets only the
samples (encoder x_c, x_s, measured p and f), as the controller does.
"""
import math
import time
from types import SimpleNamespace

import numpy as np
import pytest

from bellows_ros import interfaces
from bellows_ros.config.actuator import load_actuator
from bellows_ros.doctor import actuator_causes, live
from bellows_ros.models.actuator_plant import ActuatorPlant

CONFIG = load_actuator()
DT = 1e-3
LEAK = 1e-11        # m³/(s·Pa): the YAML's default leak
T_LEAK = 30.0


def plant_run(seconds, leak_at=None, effect=('air_leak', LEAK), seed=1):
    """Return samples (t, encoder x_c, x_s, p, f) of the plant moved by its motor."""
    plant = ActuatorPlant(CONFIG.model, CONFIG.plant, effects=['wall_bulging', 'buckling'],
                          seed=seed, x_c0=0.04)
    rows = []
    for k in range(int(round(seconds / DT))):
        t = k * DT
        if leak_at is not None and abs(t - leak_at) < DT / 2:
            plant.set_strengths(dict([effect]))
        duty = 0.3 * math.copysign(1.0, math.sin(2 * math.pi * t / 6.0))
        s = plant.step(DT, duty, x_s_imposed=0.0)
        rows.append((s.t, plant.x_from_counts(s.encoder_counts), s.x_s, s.p, s.f))
    return np.array(rows)


@pytest.fixture(scope='module')
def healthy():
    return plant_run(60.0)


@pytest.fixture(scope='module')
def leaking():
    return plant_run(60.0, leak_at=T_LEAK)


def feed(health, data, every=1000):
    """Feed `data` in 1 s chunks; return the state after each."""
    states = []
    for start in range(0, len(data), every):
        chunk = data[start:start + every]
        states.append((chunk[-1, 0], health.update(dict(zip(live.COLUMNS, chunk.T)))))
    return states


def test_ring_buffer_keeps_the_last_samples_in_order():
    ring = live.RingBuffer(5)
    for k in range(8):
        ring.append((k, 0.0, 0.0, 1e5, 0.0))
    assert list(ring.last(10)['t']) == [3, 4, 5, 6, 7]
    assert list(ring.last(2)['t']) == [6, 7]
    rows, count = ring.since(6)
    assert list(rows['t']) == [6, 7] and count == 8
    rows, count = ring.since(0)                 # older than held: what is left
    assert list(rows['t']) == [3, 4, 5, 6, 7]
    assert len(ring.since(8)[0]['t']) == 0


def test_one_message_per_sample_goes_into_the_buffer_whole():
    from bellows_ros.nodes.stiffness_controller_node import StiffnessControllerNode
    doctor = live.LiveDoctor(CONFIG, rate=10.0)
    node = SimpleNamespace(
        live=doctor,
        counts=dict.fromkeys(['samples_without_pressure', 'samples_without_force'], 0),
        sample_index=interfaces.SampleIndex(interfaces.actuator_sample_names()),
        _last_stamp=None, samples=0, _elapsed=0.0, control_every=10 ** 6)

    def sample(ns, x_c, x_s, f, p, names=('air_chamber', 'spring', 'actuator')):
        # as the driver publishes it: the spring's effort the force, the chamber's the pressure
        values = {'air_chamber': (x_c, math.nan), 'spring': (x_s, f), 'actuator': (math.nan, p)}
        StiffnessControllerNode.on_sample(node, SimpleNamespace(
            name=list(names), position=[values[n][0] for n in names],
            effort=[values[n][1] for n in names], stamp_ns=ns))

    assert interfaces.actuator_sample_names() == ('air_chamber', 'spring', 'actuator')
    sample(1_000_000, 0.01, 0.0, 3.0, 1.2e5)
    sample(2_000_000, 0.02, 0.001, math.nan, 1.3e5)      # no force: controlled, not compared
    sample(3_000_000, 0.03, 0.002, 4.0, math.nan)        # no pressure: neither
    sample(4_000_000, 0.04, 0.003, 5.0, 1.4e5, names=('spring', 'actuator', 'air_chamber'))
    sample(5_000_000, 0.05, 0.004, 6.0, 1.5e5, names=('air_chamber', 'spring'))  # not ours
    rows = doctor.buffer.last(5)
    assert [list(rows[c]) for c in live.COLUMNS] == [
        [0.001, 0.004], [0.01, 0.04], [0.0, 0.003], [1.2e5, 1.4e5], [3.0, 5.0]]
    assert node.counts == {'samples_without_pressure': 1, 'samples_without_force': 1}
    assert node.samples == 3
    mean_us, max_us = doctor.cost_us()
    assert 0.0 < mean_us and 0.0 < max_us      # counted per sample buffered


def test_a_healthy_run_stays_within_the_floor(healthy):
    health = live.ModelHealth(CONFIG.model, calibration=20.0, window=5.0)
    states = feed(health, healthy)
    assert {s for t, s in states if t < 19.0} == {'calibrating'}
    assert {s for t, s in states if t > 21.0} == {'healthy'}, states
    values = health.values()
    # The floors come from the data: the plant's pressure and force noise.
    sensors = CONFIG.plant.sensors
    assert 0.8 < values['noise_floor_p'] / sensors.pressure_noise < 1.25, values
    assert 0.8 < values['noise_floor_f'] / sensors.force_noise < 1.25, values
    assert values['ratio_p'] < values['limit_p'] and values['ratio_f'] < values['limit_f']
    assert values['limit_p'] >= live.LIMIT_MIN


def test_a_leak_switched_on_leaves_the_floor_within_seconds(leaking):
    health = live.ModelHealth(CONFIG.model, calibration=20.0, window=5.0)
    states = feed(health, leaking)
    out = [t for t, s in states if s == 'out of floor']
    assert out and all(t > T_LEAK for t in out), states
    assert out[0] - T_LEAK < 15.0, states      # sample time, not wall-clock
    assert health.values()['ratio_p'] > health.values()['limit_p']


def test_the_live_doctor_names_the_leak_with_its_size(leaking):
    doctor = live.LiveDoctor(CONFIG, calibration=20.0, window=5.0, diagnosis_s=20.0,
                             time_bound=120.0, rediagnose_s=0.0)
    try:
        for row in leaking:
            doctor.sample(*row)
            if int(round(row[0] / DT)) % 1000 == 0:
                doctor.update()
                assert doctor.health.state != 'out of floor' or row[0] > T_LEAK
        mean_us, max_us = doctor.cost_us()
        assert 0.0 < mean_us <= max_us          # counted, not bounded here (no wall clock)
        # The first window (submitted as the residual left the floor) holds the leak's first
        # seconds: it names it; the next, refreshed while the residual stays out, sizes it.
        verdicts = []
        end = time.monotonic() + 150.0
        while len(verdicts) < 2 and time.monotonic() < end:
            seen = doctor.diagnoses
            doctor.update()
            if doctor.diagnoses > seen:
                verdicts.append(doctor.verdict)
            time.sleep(0.1)
        assert len(verdicts) == 2, verdicts
        assert all(v['error'] is None and v['causes'][0] == 'air_leak' for v in verdicts), verdicts
        verdict = verdicts[-1]
        fitted = verdict['values']['air_leak']['conductance']
        assert 0.5 * LEAK < fitted < 2.0 * LEAK, verdict
        assert 'air_leak (conductance' in live.describe(verdict)
    finally:
        doctor.close()


def test_the_healthy_window_names_nothing(healthy):
    floors = actuator_causes.noise_floors({'p': healthy[:20000, 3], 'f': healthy[:20000, 4]})
    rows = dict(zip(live.COLUMNS, healthy[-20000:].T))
    verdict = live.diagnose_window(CONFIG, rows, floors)
    assert verdict['error'] is None and verdict['causes'] == [], verdict


def compressing_run(seconds, scale=None, at=20.0, seed=3):
    """Return samples of the plant whose spring is cycled 0-24 mm; buckling x `scale` from `at`."""
    plant = ActuatorPlant(CONFIG.model, CONFIG.plant, effects=['wall_bulging', 'buckling'],
                          seed=seed, x_c0=0.04)
    rows = []
    for k in range(int(round(seconds / DT))):
        t = k * DT
        if scale is not None and abs(t - at) < DT / 2:
            plant.set_strengths({'buckling': scale})
        duty = 0.3 * math.copysign(1.0, math.sin(2 * math.pi * t / 6.0))
        s = plant.step(DT, duty, x_s_imposed=0.012 * (1.0 - math.cos(2 * math.pi * t / 4.0)))
        rows.append((s.t, plant.x_from_counts(s.encoder_counts), s.x_s, s.p, s.f))
    return np.array(rows)


def test_the_live_baseline_keeps_the_models_own_buckling_and_names_a_change_of_it():
    """
    The model's own buckling is standing physics, not a fault; a spring buckling more is one.

    The spring is compressed past the model's onset in both runs. The live doctor's baseline is
    the model the monitor compares with (its E_V and buckling in it), so the healthy window names
    nothing, and a stiffness loss doubled is named with the onset where the model has it.
    """
    assert actuator_causes.standing_physics(CONFIG.model) == ('wall_bulging', 'buckling')
    b = CONFIG.model.buckling
    for scale in (None, 2.0):
        data = compressing_run(40.0, scale)
        floors = actuator_causes.noise_floors({'p': data[:20000, 3], 'f': data[:20000, 4]})
        verdict = live.diagnose_window(CONFIG, dict(zip(live.COLUMNS, data[-20000:].T)), floors)
        if scale is None:
            assert verdict['error'] is None and verdict['causes'] == [], verdict
            continue
        assert verdict['causes'] == ['buckling'], verdict
        fitted = verdict['values']['buckling']
        assert 0.8 * scale < fitted['stiffness_loss'] / b.stiffness_loss < 1.2 * scale, verdict
        assert 0.8 < fitted['critical_pressure'] / b.critical_pressure < 1.25, verdict
        assert 0.8 < fitted['critical_compression'] / b.critical_compression < 1.25, verdict


def test_the_worker_runs_one_job_at_a_time_and_kills_one_over_its_bound():
    worker = live.DiagnosisWorker(time_bound=1.0)
    try:
        assert worker.submit(time.sleep, 30.0)
        assert not worker.submit(math.sqrt, 4.0)    # one at a time
        end = time.monotonic() + 30.0
        result = None
        while result is None and time.monotonic() < end:
            result = worker.poll()
            time.sleep(0.05)
        assert result is not None and 'timed out' in result['error'], result
        assert not worker.busy
        assert worker.submit(math.sqrt, 4.0)        # a new process takes the next job
        end = time.monotonic() + 60.0
        result = None
        while result is None and time.monotonic() < end:
            result = worker.poll()
            time.sleep(0.05)
        assert result == 2.0
    finally:
        worker.close()


class InlineWorker:
    """A `DiagnosisWorker` stand-in running the job at once (tests the status, not the process)."""

    busy = False

    def __init__(self):
        self.result = None

    def submit(self, function, *args):
        self.result = function(*args)
        return True

    def poll(self):
        result, self.result = self.result, None
        return result

    def close(self):
        pass


def test_the_controllers_model_health_status_says_each_state(leaking):
    """The status the controller publishes: STALE, calibrating, healthy, WARN naming the leak."""
    from types import SimpleNamespace

    from bellows_ros.nodes import diagnostics
    from bellows_ros.nodes.stiffness_controller_node import StiffnessControllerNode
    doctor = live.LiveDoctor(CONFIG, calibration=20.0, window=5.0, worker=InlineWorker())
    node = SimpleNamespace(live=doctor, counts={'samples_without_force': 0},
                           _health_update_ms=math.nan)

    def report():
        stat = diagnostics.DiagnosticStatusWrapper()
        StiffnessControllerNode.diagnose_model_health(node, stat)
        return stat

    assert report().level == diagnostics.STALE
    seen = []
    for k, row in enumerate(leaking):
        doctor.sample(*row[:5])
        if k % 1000 == 999:
            stat = report()
            seen.append((row[0], stat.level, stat.message, stat.get('state')))
    assert {(m.split(':')[0], s) for t, lv, m, s in seen if t < 19.0} == {
        ('calibrating', 'calibrating')}
    assert {lv for t, lv, m, s in seen if t < T_LEAK} == {diagnostics.OK}
    warns = [(t, m) for t, lv, m, s in seen if lv == diagnostics.WARN]
    assert warns and warns[0][0] > T_LEAK, seen
    assert warns[0][1].endswith(': diagnosing'), warns   # submitted; collected at the next report
    assert 'air_leak (conductance' in warns[1][1], warns
    stat = report()
    for key in ('residual_rms_p', 'noise_floor_p', 'ratio_p', 'limit_p', 'window_s',
                'cost_per_sample_us', 'update_ms', 'diagnosis'):
        assert stat.get(key) is not None, key
    assert float(stat.get('ratio_p')) > float(stat.get('limit_p'))


def stepping_run(seconds, effect, at):
    """Return samples of the plant whose chamber a P loop steps between 24 and 30 mm every 4 s."""
    plant = ActuatorPlant(CONFIG.model, CONFIG.plant, effects=['wall_bulging', 'buckling'],
                          seed=2, x_c0=0.0244)
    rows, x = [], 0.0244
    for k in range(int(round(seconds / DT))):
        t = k * DT
        if abs(t - at) < DT / 2:
            plant.set_strengths(dict([effect]))
        target = 0.0244 if (t // 4) % 2 == 0 else 0.0304
        s = plant.step(DT, max(-0.8, min(0.8, 400.0 * (target - x))), x_s_imposed=0.0)
        x = plant.x_from_counts(s.encoder_counts)
        rows.append((s.t, x, s.x_s, s.p, s.f))
    return np.array(rows)


def test_a_sensor_lag_switched_on_is_named_with_its_time_constant():
    tau = 0.1
    data = stepping_run(60.0, ('sensor_lag', tau), at=T_LEAK)
    health = live.ModelHealth(CONFIG.model, calibration=20.0, window=5.0)
    states = feed(health, data)
    out = [t for t, s in states if s == 'out of floor']
    assert out and min(out) > T_LEAK, states
    # The force is not lagged: only the pressure leaves its floor.
    assert health.values()['ratio_f'] < health.values()['limit_f']
    verdict = live.diagnose_window(CONFIG, dict(zip(live.COLUMNS, data[-20000:].T)),
                                   health.floors)
    assert verdict['causes'] == ['sensor_lag'], verdict
    assert 0.7 * tau < verdict['values']['sensor_lag']['time_constant'] < 1.3 * tau, verdict


def test_a_gas_amount_identified_a_little_off_is_not_a_fault(healthy):
    """The healthy window's offset is the reference: a p_ref 300 Pa off stays within the floor."""
    import dataclasses
    off = dataclasses.replace(CONFIG.model, p_ref=CONFIG.model.p_ref + 300.0)
    health = live.ModelHealth(off, calibration=20.0, window=5.0)
    states = feed(health, healthy)
    assert {s for t, s in states if t > 21.0} == {'healthy'}, states
    assert abs(health.offsets['p']) > 10 * health.floors['p']   # the offset is really there
