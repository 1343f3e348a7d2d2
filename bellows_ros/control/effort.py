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
Control effort of a pressure-driven segment: how much the valves move and how much air they use.

Three figures, over the commands at the valves and the chamber pressures of a run (Pa abs, one row
per sample at a fixed step):

- command variation, Pa/s: Σ_j Σ_k |p_cmd,j[k+1] - p_cmd,j[k]| over both chains, per second of
  run. What the valves are asked to travel; chatter shows here first.
- air used, NL per L of chain volume: the air admitted to the chambers, Σ_j ∫ max(0, ṗ_j) dt / p_n
  with p_n = 101325 Pa. For a chamber of fixed volume V at constant temperature the mass admitted
  is V/(R T) ∫ max(0, ṗ) dt (the gas law); divided by the density of air at p_n and the same T,
  that is normal litres per litre of chamber volume. Every admitted mass is vented again later, so
  this is also the air the run blows off. The segment's model has no chamber volume (paper A's
  bellows volume changes with Ψ and is not in the model), so the figure is per unit volume:
  multiply by a chain's volume in litres for NL. Computed from the true chamber pressure, i.e.
  through the valve model's lag (what the valves actually pass), not from the commands.
- hold chatter, Pa: in each hold of the set-point (after `settle` s), the larger of the two chains'
  peak-to-peak command; the median and the worst over the holds.
"""
import numpy as np

P_NORMAL = 101325.0  # Pa, the "normal" in normal litres


def command_variation(t, *commands):
    """Return Σ over chains of Σ|Δp_cmd| per second, Pa/s (t in s, commands in Pa)."""
    span = float(t[-1] - t[0])
    total = sum(float(np.abs(np.diff(np.asarray(c, float))).sum()) for c in commands)
    return total / span if span > 0 else float('nan')


def air_used(*pressures):
    """Return Σ over chains of ∫ max(0, ṗ) dt / P_NORMAL: NL per L of chain volume."""
    return sum(float(np.clip(np.diff(np.asarray(p, float)), 0.0, None).sum())
               for p in pressures) / P_NORMAL


def hold_chatter(t, holding, commands, settle=0.3):
    """
    Peak-to-peak of the commands in each hold, Pa: (median, worst) over the holds.

    t s; holding: bool per sample, True where the set-point holds; commands: one array per chain.
    Each hold's first `settle` s are left out (the end of the move settles there); holds shorter
    than twice that are skipped. (nan, nan) without a hold.
    """
    holding = np.asarray(holding, bool)
    edges = np.flatnonzero(np.diff(holding.astype(int))) + 1
    swings = []
    for rows in np.split(np.arange(len(holding)), edges):
        if not holding[rows[0]] or t[rows[-1]] - t[rows[0]] < 2.0 * settle:
            continue
        rows = rows[t[rows] >= t[rows[0]] + settle]
        swings.append(max(float(np.ptp(np.asarray(c)[rows])) for c in commands))
    if not swings:
        return float('nan'), float('nan')
    return float(np.median(swings)), float(max(swings))
