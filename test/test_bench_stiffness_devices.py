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
The stiffness controller on drawn actuators (`bellows bench --only stiffness_devices`).

The bench identifies each device from its own record, as a user would: sealed first, with the
leak (`bellows identify actuator --leak`) where that fails. The device's leak is hidden from the
fit; the test compares the fitted conductance with it.
"""
import re

import pytest

from bellows_ros.bench import stiffness_devices as bench


@pytest.mark.parametrize('index', [4, 8])
def test_a_leaking_device_is_identified_with_its_leak(index):
    device = bench.draw_actuator(bench.SEED + index)
    fitted, how = bench.identify(device)
    assert fitted is not None and how.startswith('with a leak'), how
    leak = float(re.search(r'G = (\S+) m\^3', how).group(1))
    assert leak == pytest.approx(device.effects['air_leak']['conductance'], rel=0.1)


@pytest.mark.slow  # two devices, four 8 s steps each with both maps at 1 kHz
def test_the_quick_bench_reports_both_maps_and_what_was_fitted():
    identified, default = bench.run(quick=True)
    assert identified.name.endswith('identified_map.step_time')
    assert default.name.endswith('default_map.step_time') and default.samples == 8
    fits, failed = identified.extra['fits'], identified.extra['failures']
    failures = int(identified.extra['identification_failed'].split()[0])
    assert identified.samples == 4 * (2 - failures)
    assert (fits == 'none') == (identified.samples == 0) and (failed == 'none') == (
        identified.samples == 8)
    for result in (identified, default):
        assert 0.0 <= result.extra['median_error'] <= result.extra['worst_error']
