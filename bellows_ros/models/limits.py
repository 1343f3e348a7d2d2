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
Upper bounds on the device parameters that size a computation, checked when parameters load.

Wide on purpose (any pneumatic bellows of a soft arm or a stiffness actuator, not this package's
default one), and tight enough that a unit mistake or an absurd value is refused with its name
before the model allocates or loops on it: a length written in mm (50 for 0.05 m) is 50 "m",
and a strain profile of 10⁹ samples would take gigabytes per chain.
"""
# m: the longest length of a bellows' geometry. Soft-arm segments and actuator bellows are a few
# cm (papers A and B: 0.05-0.08 m); one metre is past any of them.
MAX_LENGTH = 1.0
# Samples of a chain's stored strain profile (Algorithm 1, (28)): 10⁵ is 1 µm steps over 10 cm,
# far finer than a membrane's contact is known; each sample costs memory and time per step.
MAX_PROFILE_SAMPLES = 100_000
# Segments (convolutions) of one bellows: tens in practice; the equations loop over none, but a
# count in the thousands is a typing mistake.
MAX_CONVOLUTIONS = 1000
# Pa abs: ambient pressure, about 50 kPa 5000 m up to 108 kPa at the lowest places on earth; a p0
# outside it was written in bar, kPa or hPa.
AMBIENT_RANGE = (5e4, 1.1e5)
# s: time constants of valves, sensors and wall heat transfer, from 0.1 ms (fast piezo valves) to
# hours (a thermally insulated chamber).
TIME_CONSTANT = (1e-4, 1e4)
