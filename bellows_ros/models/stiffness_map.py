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
Inverse map for the stiffness controller.

Target stiffness (or pressure) -> air-chamber compression.

The stiffness K(x_c) of `actuator.stiffness` (paper B's average slope over spring 0-12 mm) rises
with the chamber compression because the pressure does, until the spring starts to buckle
(`actuator.buckling_force`): from there on more pressure costs stiffness, and K falls towards the
fully compressed end stop (paper B: 1975 N/m at 20 mm, 1913 N/m at 48 mm). K(x_c) is then not
one-to-one. The map uses the **rising branch** only, x_c from the elongated end stop to the
compression of the first peak of the stiffness, x_peak: with the default parameters it reaches
every stiffness the actuator can give (the falling branch repeats values of the rising one), at
the lower pressure, away from buckling; `reachable` reports the stiffness at the compressed end
stop as well. Without buckling x_peak is the compressed end stop.

The inverse is read from a table K(p_ref, x_c) precomputed once per parameter set
(`StiffnessMap`), then polished by one Newton step on the exact model, so the answer is exact to
well below the controller's 0.5 % tolerance at a few model evaluations per query.

The function forms (`compression_for_stiffness`, ...) keep one `StiffnessMap` per parameter object
in a small cache, so calling them in a 1 kHz loop costs the table lookup, not the table.
"""
from scipy.optimize import brentq, minimize_scalar

from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator import pressure, stiffness

_GAS_SPAN = (0.80, 1.20)    # table covers p_ref from 80 % to 120 % of the YAML's p_ref
_GAS_NODES = 17
_X_NODES = 96
BRANCH = 'rising'           # the branch of K(x_c) the map inverts (module docstring)


class StiffnessMap:
    """
    Precomputed K(p_ref, x_c) table with exact-model polishing (see module docstring).

    Building costs about _GAS_NODES x _X_NODES x 2 model evaluations (a few tens of ms), plus a
    peak search per gas node when the stiffness is not monotone.
    """

    def __init__(self, params):
        self.params = params
        c = params.chamber
        self.x_min, self.x_max = c.x_min, c.x_max
        step = (self.x_max - self.x_min) / (_X_NODES - 1)
        self.x_nodes = [self.x_min + i * step for i in range(_X_NODES)]
        low, high = (params.p_ref * f for f in _GAS_SPAN)
        self.gas_step = (high - low) / (_GAS_NODES - 1)
        self.gas_nodes = [low + j * self.gas_step for j in range(_GAS_NODES)]
        self.table = [[stiffness(params, x, gas) for x in self.x_nodes] for gas in self.gas_nodes]
        self.peaks = [self._peak(gas, row) for gas, row in zip(self.gas_nodes, self.table)]
        for gas, row, (x_peak, _) in zip(self.gas_nodes, self.table, self.peaks):
            rising = [k for x, k in zip(self.x_nodes, row) if x <= x_peak]
            if any(b <= a for a, b in zip(rising, rising[1:])):
                raise ParameterError(
                    f'actuator: stiffness is not monotone in the chamber compression below '
                    f'its peak at p_ref = {gas:.0f} Pa; check actuator.air_chamber.x_min/x_max '
                    'and the force parameters')

    def _peak(self, gas, row=None):
        """(x_peak, k_peak): compression (m) and value (N/m) of the first peak of K(x_c)."""
        if row is None:
            row = [stiffness(self.params, x, gas) for x in self.x_nodes]
        # The first local maximum: at a high gas amount the exponential E_F (11) of the buckled
        # spring can make K rise again near the compressed end stop, far outside paper B's data.
        i = next((i for i in range(len(row) - 1) if row[i + 1] < row[i]), len(row) - 1)
        if i == len(row) - 1:
            return self.x_max, row[-1]
        lo, hi = self.x_nodes[max(i - 1, 0)], self.x_nodes[i + 1]
        best = minimize_scalar(lambda x: -stiffness(self.params, x, gas), bounds=(lo, hi),
                               method='bounded', options={'xatol': 1e-7})
        return float(best.x), float(-best.fun)

    def _gas_position(self, gas):
        g = self.params.p_ref if gas is None else gas
        j_float = (g - self.gas_nodes[0]) / self.gas_step
        if not 0.0 <= j_float <= _GAS_NODES - 1:
            return g, None, None
        j = min(int(j_float), _GAS_NODES - 2)
        return g, j, j_float - j

    def _peak_near(self, gas):
        """`_peak` for gas amount `gas`, from the table's peaks when `gas` is inside its span."""
        g, j, w = self._gas_position(gas)
        if j is None:
            return self._peak(g)
        x0, x1 = self.peaks[j][0], self.peaks[j + 1][0]
        guess = x0 + w * (x1 - x0)
        if guess >= self.x_max:
            return self.x_max, stiffness(self.params, self.x_max, g)
        step = self.x_nodes[1] - self.x_nodes[0]
        lo, hi = max(self.x_min, guess - step), min(self.x_max, guess + step)
        best = minimize_scalar(lambda x: -stiffness(self.params, x, g), bounds=(lo, hi),
                               method='bounded', options={'xatol': 1e-7})
        return float(best.x), float(-best.fun)

    def branch(self, gas=None):
        """(x_low, x_high), m: the rising branch of K(x_c) the map uses for gas amount `gas`."""
        return self.x_min, self._peak_near(gas)[0]

    def range(self, gas=None):  # noqa: A003 (the public name; a method cannot shadow it)
        """
        Return (k_min, k_max), N/m, on the rising branch for gas amount `gas` (p_ref, Pa).

        The stiffness at the elongated end stop and at the peak.
        """
        g = self.params.p_ref if gas is None else gas
        return stiffness(self.params, self.x_min, g), self._peak_near(g)[1]

    def reachable(self, gas=None):
        """
        Tell what the actuator can give with gas `gas`, for reports.

        A dict with the branch used (x_low, x_high, k_low, k_high) and the stiffness at the
        compressed end stop (k_end).
        """
        g = self.params.p_ref if gas is None else gas
        x_low, x_high = self.branch(g)
        k_low, k_high = self.range(g)
        return {'branch': BRANCH, 'x_low': x_low, 'x_high': x_high, 'k_low': k_low,
                'k_high': k_high, 'k_end': stiffness(self.params, self.x_max, g)}

    def compression(self, k_target, gas=None):
        """Chamber compression x_c (m) on the rising branch where the stiffness is `k_target`."""
        params = self.params
        g, j, w = self._gas_position(gas)
        if j is None:
            return self._solve(k_target, g)        # outside the table: exact root finding
        row0, row1 = self.table[j], self.table[j + 1]
        x_peak = min(self.peaks[j][0], self.peaks[j + 1][0])
        top = max(i for i, x in enumerate(self.x_nodes) if x <= x_peak)
        k_low = row0[0] + w * (row1[0] - row0[0])
        k_high = row0[top] + w * (row1[top] - row0[top])
        if top < 1 or not k_low <= k_target <= k_high:
            return self._solve(k_target, g)        # near or beyond the range: decide exactly
        # Bisection on the gas-interpolated row, then linear interpolation in the cell.
        lo, hi = 0, top
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if row0[mid] + w * (row1[mid] - row0[mid]) < k_target:
                lo = mid
            else:
                hi = mid
        k_lo = row0[lo] + w * (row1[lo] - row0[lo])
        k_hi = row0[hi] + w * (row1[hi] - row0[hi])
        slope = (k_hi - k_lo) / (self.x_nodes[hi] - self.x_nodes[lo])
        x = self.x_nodes[lo] + (k_target - k_lo) / slope
        # One Newton step on the exact model, with the cell's slope (secant) as the derivative.
        x += (k_target - stiffness(params, x, g)) / slope
        return min(max(x, self.x_min), self.x_max)

    def _solve(self, k_target, gas):
        x_peak, k_max = self._peak_near(gas)
        k_min = stiffness(self.params, self.x_min, gas)
        if not k_min <= k_target <= k_max:
            k_end = stiffness(self.params, self.x_max, gas)
            extra = ''
            if k_end < k_target < k_min:
                extra = (f'; the buckled spring reaches it only past the peak at x_c = '
                         f'{x_peak * 1e3:.1f} mm, a branch this map does not use')
            raise ParameterError(
                f'stiffness {k_target:.1f} N/m is outside the achievable range '
                f'[{k_min:.1f}, {k_max:.1f}] N/m (gas p_ref = {gas:.0f} Pa; {BRANCH} branch x_c '
                f'{self.x_min * 1e3:.1f}-{x_peak * 1e3:.1f} mm){extra}')
        return brentq(lambda x: stiffness(self.params, x, gas) - k_target,
                      self.x_min, x_peak, xtol=1e-9)


_maps = {}


def stiffness_map(params):
    """Return the cached `StiffnessMap` of `params` (built on first use)."""
    entry = _maps.get(id(params))
    if entry is None or entry[0] is not params:
        if len(_maps) >= 8:
            _maps.clear()
        entry = (params, StiffnessMap(params))
        _maps[id(params)] = entry
    return entry[1]


def compression_for_stiffness(params, k_target, gas=None):
    """
    Air-chamber compression x_c (m) on the rising branch giving stiffness `k_target` (N/m).

    `gas` is the gas amount as p_ref (Pa; default the YAML's), e.g. from `actuator.estimate_gas`.
    Monotone in `k_target`. Raises ParameterError naming the achievable range when outside it.
    """
    return stiffness_map(params).compression(float(k_target), gas)


def stiffness_range(params, gas=None):
    """(k_min, k_max), N/m: the stiffness at the elongated end stop and at the peak of K(x_c)."""
    return stiffness_map(params).range(gas)


def stiffness_branch(params, gas=None):
    """(x_low, x_high), m: the chamber compressions of the rising branch the map inverts."""
    return stiffness_map(params).branch(gas)


def compression_for_pressure(params, p_target, x_s=0.0, gas=None):
    """Air-chamber compression x_c (m) at which the pressure is `p_target` (Pa), spring at x_s."""
    c = params.chamber
    p_low, p_high = (pressure(params, x, x_s, gas) for x in (c.x_min, c.x_max))
    if not p_low <= p_target <= p_high:
        raise ParameterError(f'pressure {p_target:.0f} Pa is outside the achievable range '
                             f'[{p_low:.0f}, {p_high:.0f}] Pa at spring compression {x_s:g} m')
    return brentq(lambda x: pressure(params, x, x_s, gas) - p_target, c.x_min, c.x_max, xtol=1e-10)
