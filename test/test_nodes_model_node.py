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
model_node's torques, the node in the test's process: what it publishes is the model's own.

A feeder node publishes a made-up stream of samples on /joint_states, as the driver does; the
test steps its own `SegmentModel`s on the same stream and computes τ_ext (2) with Ψ̈ from
successive Ψ̇ (`derivatives.rate`), under parameters with non-zero M, C and N, so τ_ext is not
just −τ_drive. The node's two topics must carry those numbers, sample by sample, with the
samples' stamps.
"""
import math
import random
import time

import probe
import pytest
import yaml

from bellows_ros.config.segment import load_segment_params
from bellows_ros.interfaces import SAMPLE_DEPTH
from bellows_ros.models.derivatives import rate
from bellows_ros.models.segment import external_torque, SegmentModel
from bellows_ros.nodes import diagnostics
from bellows_ros.nodes.model_node import MAX_MISSED_GAP, ModelNode

pytestmark = pytest.mark.realtime  # runs alone, after the others (scripts/test.sh)

DOMAIN = '194'
DYNAMICS = {'segment': {'dynamics': {'inertia': 0.02, 'damping': 0.1, 'gravity': 0.3}}}


@pytest.fixture
def feeder(monkeypatch, tmp_path):
    monkeypatch.setenv('ROS_DOMAIN_ID', DOMAIN)
    params_file = tmp_path / 'dynamics.yaml'
    params_file.write_text(yaml.safe_dump({'/**': {'ros__parameters': DYNAMICS}}))
    probe.init(['--ros-args', '-p', f'model_node:params_file:={params_file}',
                '-p', 'model_node:segments:=[1, 2]'])
    yield probe.adopt(ModelNode()), probe.Node('feeder'), params_file
    probe.shutdown()


def _stream(count, seed=3):
    """(stamp ns, Ψ, Ψ̇, chain pressures) per sample for two segments: a wandering motion."""
    rng = random.Random(seed)
    psi = [0.0, 0.1]
    for k in range(count):
        psi_dot = [0.8 * math.sin(0.02 * k + i) + 0.05 * rng.uniform(-1, 1) for i in range(2)]
        psi = [a + 1e-3 * b for a, b in zip(psi, psi_dot)]
        pressures = [2.0e5 + 1.0e5 * math.sin(0.01 * k + j) for j in range(4)]
        yield 1_700_000_000_000_000_000 + k * 1_000_000, psi, psi_dot, pressures


def _feed(node, peer, stream, expected=None):
    """
    Publish `stream`'s samples to `node` from `peer`; return what node published, by topic.

    Waits until `expected` torques (default: one per sample) have come back, or 10 s.
    """
    msg = probe.msg
    received = {'/bellows/driving_torque': [], '/bellows/external_torque': []}
    for topic, out in received.items():
        peer.create_subscription(msg.JointState, topic, out.append, SAMPLE_DEPTH)
    joints = peer.create_publisher(msg.JointState, '/joint_states', SAMPLE_DEPTH)
    end = time.monotonic() + 10.0
    while (joints.get_subscription_count() < 1 or node.drive_pub.get_subscription_count() < 1) \
            and time.monotonic() < end:
        probe.spin_once(peer, timeout_sec=0.05)

    for stamp, psi, psi_dot, pressures in stream:
        joints.publish(probe.arm_sample(stamp, psi, psi_dot, pressures, segments=(1, 2)))
        probe.spin_once(node, timeout_sec=0.0)   # the node serves as it would spinning
    end = time.monotonic() + 10.0
    expected = len(stream) if expected is None else expected
    while min(len(v) for v in received.values()) < expected and time.monotonic() < end:
        probe.spin_once(node, timeout_sec=0.01)
        probe.spin_once(peer, timeout_sec=0.01)
    return received


def test_the_topics_carry_the_models_torques_sample_by_sample(feeder):
    node, peer, params_file = feeder
    stream = list(_stream(200))
    names = ['segment_1', 'segment_2']
    received = _feed(node, peer, stream)
    assert [len(v) for v in received.values()] == [len(stream)] * 2
    assert node.counts['evaluated'] == len(stream)

    params = load_segment_params(params_file)
    assert (params.dynamics_inertia, params.dynamics_damping) == (0.02, 0.1)
    models = [SegmentModel(params) for _ in names]
    previous, held, last_stamp = [None, None], [0.0, 0.0], None
    for k, (stamp, psi, psi_dot, pressures) in enumerate(stream):
        dt = 0.0 if last_stamp is None else (stamp - last_stamp) * 1e-9
        last_stamp = stamp
        drive, external = received['/bellows/driving_torque'][k], \
            received['/bellows/external_torque'][k]
        for message in (drive, external):
            assert message.name == names
            assert message.header.stamp.sec * 1_000_000_000 + message.header.stamp.nanosec == stamp
        for i in range(2):
            tau = models[i].step(psi[i], psi_dot[i], *pressures[2 * i:2 * i + 2]).tau_drive
            held[i] = rate(psi_dot[i], previous[i], dt, held[i])
            previous[i] = psi_dot[i]
            assert drive.effort[i] == pytest.approx(tau, rel=1e-12, abs=1e-15)
            assert external.effort[i] == pytest.approx(
                external_torque(params, psi[i], psi_dot[i], held[i], tau), rel=1e-12, abs=1e-15)
    # The motion made Ψ̈ and N matter: τ_ext is not merely −τ_drive.
    assert max(abs(e.effort[0] + d.effort[0]) for d, e in
               zip(*received.values())) > 1e-3

    # /diagnostics: the evaluation OK, then STALE once the samples stop; the latency status ERROR
    # (the stream's stamps are of 2023, the node clock is now: far later than latency_budget).
    def report():
        return {s.name: s for s in node.diagnostics.force_update()}
    first = report()
    evaluation, latency = first['driving torque'], first['latency']
    assert (evaluation.level, evaluation.hardware_id) == (diagnostics.OK, 'none')
    assert evaluation.message.startswith('evaluating') and evaluation.get('evaluated') == '200'
    assert evaluation.get('rejected') == '0'
    assert evaluation.get('missed') == '0'
    assert (latency.level, latency.message) == (diagnostics.ERROR,
                                                'Timestamps too far in past seen.')
    silent = report()
    assert silent['driving torque'].level == diagnostics.STALE
    assert silent['driving torque'].message.startswith('no samples since the last report')
    assert (silent['latency'].level, silent['latency'].message) == (
        diagnostics.WARN, 'No data since last update.')


def test_samples_that_never_arrived_are_counted_from_the_stamp_gaps(feeder):
    """
    A gap of n sample periods in the stamps is n - 1 samples lost before the node.

    It counts them and warns; a pause longer than a queue could hold is not a loss.
    """
    node, peer, _ = feeder
    stream = list(_stream(300))
    lost = set(range(50, 53)) | {120} | set(range(200, 210))    # 3 + 1 + 10 samples
    kept = [sample for k, sample in enumerate(stream) if k not in lost]
    # A sample that arrives but is rejected (a pressure of NaN) is not missed: it is counted once.
    stamp, psi, psi_dot, pressures = kept[150]
    kept[150] = (stamp, psi, psi_dot, [math.nan, *pressures[1:]])
    pause = int(2 * MAX_MISSED_GAP * 1e9)    # the driver stopped, then went on
    kept += [(stamp + pause, *rest) for stamp, *rest in _stream(20, seed=4)]
    received = _feed(node, peer, kept, expected=len(kept) - 1)
    assert [len(v) for v in received.values()] == [len(kept) - 1] * 2
    assert node.counts['missed'] == len(lost)
    assert node.counts['rejected'] == 1
    evaluation = {s.name: s for s in node.diagnostics.force_update()}['driving torque']
    assert evaluation.get('missed') == str(len(lost))
    assert evaluation.level == diagnostics.WARN
    assert f'{len(lost)} samples never arrived' in evaluation.message
