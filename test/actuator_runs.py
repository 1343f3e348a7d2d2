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

"""The default actuator and its plant, stepped the way the plant and effect tests step it."""
from bellows_ros.config.actuator import load_actuator_params, load_actuator_plant_params

PLANT = load_actuator_plant_params()

PARAMS = load_actuator_params()
SIGMA_P = PLANT.sensors.pressure_noise
DT = 1e-3


def run(plant, seconds, duty=0.0, x_s=None):
    """Step `plant` for `seconds`; x_s is a constant or a function of plant time."""
    out = []
    for _ in range(int(round(seconds / DT))):
        target = x_s(plant.t) if callable(x_s) else x_s
        out.append(plant.step(DT, duty, x_s_imposed=target))
    return out


def fast_spring_step(t, start=0.5, rise=0.05, amplitude=0.012):
    return amplitude * min(max((t - start) / rise, 0.0), 1.0)
