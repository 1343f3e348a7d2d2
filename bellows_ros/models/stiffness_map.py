"""Inverse map for the stiffness controller: target stiffness (or pressure) -> air-chamber compression.

The stiffness K(x_c) of `actuator.stiffness` (paper B's average slope over spring 0-12 mm) rises
monotonically with the chamber compression between the lead screw's end stops, because the
pressure does. The inverse is read from a table K(p_ref, x_c) precomputed once per parameter set
(`StiffnessMap`), then polished by one Newton step on the exact model, so the answer is exact to
well below the controller's 0.5 % tolerance at a few model evaluations per query.

The function forms (`compression_for_stiffness`, ...) keep one `StiffnessMap` per parameter object
in a small cache, so calling them in a 1 kHz loop costs the table lookup, not the table.
"""
from scipy.optimize import brentq

from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator import pressure, stiffness

_GAS_SPAN = (0.80, 1.20)    # table covers p_ref from 80 % to 120 % of the YAML's p_ref
_GAS_NODES = 17
_X_NODES = 96


class StiffnessMap:
    """Precomputed K(p_ref, x_c) table with exact-model polishing (see module docstring).

    Building costs about _GAS_NODES x _X_NODES x 2 model evaluations (a few tens of ms).
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
        for gas, row in zip(self.gas_nodes, self.table):
            if any(b <= a for a, b in zip(row, row[1:])):
                raise ParameterError(
                    f'actuator: stiffness is not monotone in the chamber compression at p_ref = '
                    f'{gas:.0f} Pa; check actuator.air_chamber.x_min/x_max and the force parameters')

    def range(self, gas=None):
        """(k_min, k_max), N/m, at the end stops for gas amount `gas` (p_ref, Pa)."""
        return (stiffness(self.params, self.x_min, gas), stiffness(self.params, self.x_max, gas))

    def compression(self, k_target, gas=None):
        """Chamber compression x_c (m) at which the stiffness equals `k_target` (N/m)."""
        params = self.params
        g = params.p_ref if gas is None else gas
        j_float = (g - self.gas_nodes[0]) / self.gas_step
        if not 0.0 <= j_float <= _GAS_NODES - 1:
            return self._solve(k_target, g)        # outside the table: exact root finding
        j = min(int(j_float), _GAS_NODES - 2)
        w = j_float - j
        row0, row1 = self.table[j], self.table[j + 1]
        k_low = row0[0] + w * (row1[0] - row0[0])
        k_high = row0[-1] + w * (row1[-1] - row0[-1])
        if not k_low <= k_target <= k_high:
            return self._solve(k_target, g)        # near or beyond the range: decide exactly
        # Bisection on the gas-interpolated row, then linear interpolation in the cell.
        lo, hi = 0, _X_NODES - 1
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
        k_min, k_max = self.range(gas)
        if not k_min <= k_target <= k_max:
            raise ParameterError(
                f'stiffness {k_target:.1f} N/m is outside the achievable range '
                f'[{k_min:.1f}, {k_max:.1f}] N/m (gas p_ref = {gas:.0f} Pa)')
        return brentq(lambda x: stiffness(self.params, x, gas) - k_target,
                      self.x_min, self.x_max, xtol=1e-9)


_maps = {}


def stiffness_map(params):
    """The cached `StiffnessMap` of `params` (built on first use)."""
    entry = _maps.get(id(params))
    if entry is None or entry[0] is not params:
        if len(_maps) >= 8:
            _maps.clear()
        entry = (params, StiffnessMap(params))
        _maps[id(params)] = entry
    return entry[1]


def compression_for_stiffness(params, k_target, gas=None):
    """Air-chamber compression x_c (m) giving stiffness `k_target` (N/m) with gas amount `gas`.

    `gas` is the gas amount as p_ref (Pa; default the YAML's), e.g. from `actuator.estimate_gas`.
    Monotone in `k_target`. Raises ParameterError naming the achievable range when outside it.
    """
    return stiffness_map(params).compression(float(k_target), gas)


def stiffness_range(params, gas=None):
    """(k_min, k_max), N/m: the stiffness at the lead screw's two end stops."""
    return stiffness_map(params).range(gas)


def compression_for_pressure(params, p_target, x_s=0.0, gas=None):
    """Air-chamber compression x_c (m) at which the pressure is `p_target` (Pa), spring at x_s."""
    c = params.chamber
    p_low, p_high = (pressure(params, x, x_s, gas) for x in (c.x_min, c.x_max))
    if not p_low <= p_target <= p_high:
        raise ParameterError(f'pressure {p_target:.0f} Pa is outside the achievable range '
                             f'[{p_low:.0f}, {p_high:.0f}] Pa at spring compression {x_s:g} m')
    return brentq(lambda x: pressure(params, x, x_s, gas) - p_target, c.x_min, c.x_max, xtol=1e-10)

