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
What an effect of paper B's actuator is: the contract every effect module implements.

An effect is one piece of physics beyond the doctor's baseline (paper B (17) with the geometric
volume, isothermal sealed gas, (7)-(12) without buckling) that a device may hold. One object
carries all of it, after PySINDy's library contract: the simulated plant steps it
(`plant_term`), the doctor's model predicts it over a record (the array hooks), the doctor fits
it (`fit`, `to_si`, `starts`, `edges`), judges whether a record can show it (`judged_by`) and
says what data would decide it (`deciding_data`); the YAML's and `--effect`'s ranges, the
simulated node's live strength and the benches' drawn devices come from `parameters`,
`strength` and `devices`. The registry (`actuator_effects.EFFECTS`) is every module of this
package; no other module names an effect.

The doctor's model of a record runs the hooks in this order, each effect's in `rank` order:
plate (the encoder's x_c -> the plate's), volumes, temperature, gas amount, pressure (17),
sensor; then the force (7)-(12) plus `force`. A hook an effect does not override
leaves its argument as it is.
"""
import abc
from typing import NamedTuple


class Parameter(NamedTuple):
    """A parameter of the plant's effect (`actuator.effects.<effect>.<name>`), SI units."""

    default: float   # the value the plant takes when the YAML does not set it
    low: float       # the physical range, checked in the YAML, `--effect` and live strengths
    high: float
    unit: str
    meaning: str     # what the value means (the YAML's comment, docs/actuator.md)
    hint: str = ''   # a likely mistake when a value is out of range ('was it written in °C?')


class FitVariable(NamedTuple):
    """A variable the doctor fits, scaled so that it is O(1) (`to_si` makes it SI)."""

    name: str
    start: float
    lower: float
    upper: float


class ActuatorEffect(abc.ABC):
    """
    One physical effect of the actuator: plant term, model term, fit, identifiability, docs.

    Subclasses set the class attributes and override the hooks their physics touches.
    """

    name = ''              # --effect NAME, actuator.effects.NAME.*, the doctor's cause
    rank = 0               # place in every list; never changes: the benches seed devices by it
    summary = ''           # one line of physics (docs/doctor.md's table, the report)
    parameters = {}        # {name: Parameter} of the plant's effect
    strength = ''          # the parameter that says how strong it is, 0 = off (live)
    devices = {}           # {parameter: (kind, low, high)} the benches draw devices from
    deciding_data = ''     # what a record must hold to decide it when it did not pay
    fit = ()               # FitVariables of the doctor's fit
    starts = ()            # other starts of `fit` when it is the cause added last
    edges = {}             # {(variable, 'lower'|'upper'): (kind, meaning)} (doctor.diagnosis)
    # How the doctor judges whether a record can show it: 'profile' (each fit variable across
    # its bounds, `actuator_causes.identifiability`), 'onset' (the buckling profile) or
    # 'structure' (`structural_reason`).
    judged_by = 'profile'
    # Physics the model itself may hold (E_V, buckling), kept at the model's values by the live
    # doctor's baseline: `held_by(params)` says whether it does; `baseline_text` is how the
    # baseline's name changes when it is kept: (the baseline's words, the kept words).
    standing = False
    baseline_text = ('', '')
    # Develops while the actuator runs (a leak opens, a port clogs, a spring starts to buckle):
    # the live doctor tries it. The others belong to the build (`bellows diagnose` on a record).
    in_service = False
    # Whether the plant needs `--effect NAME` to have the fitted physics; False: it is in the
    # model's own parameters (E_V), which the extended file carries.
    switched_by_effect = True

    # --- the plant's parameters ------------------------------------------------------------

    def check(self, values):
        """Return an error message for effect parameters {name: SI value} together, or None."""
        return None

    def model_params(self, params, values):
        """Return `params` (ActuatorParams) with this effect's static physics; values None: off."""
        return params

    def plant_term(self, values):
        """Return the `PlantTerm` the plant steps with these parameters, or None (static only)."""
        return None

    # --- the doctor: fit and judgement -----------------------------------------------------

    def fit_variables(self, params):
        """Return the `FitVariable`s on `params` (ActuatorParams, or None): `fit` by default."""
        return list(self.fit)

    @abc.abstractmethod
    def to_si(self, raw):
        """Fit variables {name: value} -> physical parameters {name: SI value}."""

    def from_si(self, si):
        """
        Physical parameters {name: SI value} -> fit variables {name: value}: `to_si`'s inverse.

        An effect judged by its onset implements it: its profile runs in SI, and the fit starts
        from the profile's best onsets.
        """
        raise NotImplementedError(f'effect {self.name!r} has no from_si')

    def held_by(self, params):
        """Whether the model's own parameters hold this physics (`standing` effects only)."""
        return False

    def own_start(self, params):
        """Return the model's own values of a `standing` effect as fit variables {name: value}."""
        return {}

    def structural_reason(self, record):
        """Why `record` cannot show the effect, from its structure alone, or None (`structure`)."""
        return None

    # --- the doctor's model over a record (arrays; values: `to_si`'s) ---------------------

    def plate(self, x_c, values):
        """Return the plate's compression (m) from the encoder's `x_c` (m)."""
        return x_c

    def volumes(self, params, values):
        """Change the volumes of the model `params` (ActuatorParams) as the effect does (E_V)."""
        return params

    def temperature(self, temperature, volume, dt, values):
        """Gas temperature over ambient (1 = ambient) given the total `volume` (m³) per row."""
        return temperature

    def amount(self, amount, temperature, volume, dt, values, n0):
        """Gas amount over the sealed one (1 = sealed); `n0` the sealed P V (Pa·m³)."""
        return amount

    def sensor(self, p, dt, values):
        """Return the pressure reading (Pa) of the gas pressure `p` (Pa) sampled every `dt` s."""
        return p

    def force(self, known, params, x_s, p_gas, values):
        """
        Return the spring force the model knows (N) plus this effect's, at compression x_s (m).

        `values` None: the model's own physics (`standing`), from `params`.
        """
        return known

    def extended(self, model, params, values):
        """`model` (ActuatorParams) with the fitted physics, for the extended parameter file."""
        return model

    def device(self, params, drawn):
        """Place a drawn device's `drawn` values: (`params`, the values the plant takes)."""
        return params, drawn

    def flat(self, values):
        """Return the fitted values as `actuator.effects.<name>.*` parameters {key: value}."""
        return {key: value for key, value in values.items() if key in self.parameters}


class PlantTerm:
    """
    The part of an effect the simulated plant steps, with state of its own if it needs it.

    The plant calls only the hooks a term overrides, each step, in the effects' `rank` order:
    `temperature` and `gas` before the pressure is solved, `sensor` on the reading. The plant's
    gas state is `plant.gas_amount` (N = P V at ambient temperature, Pa·m³),
    `plant.temperature` and `plant.t_ambient` (K).
    """

    def start(self, plant, previous=None):
        """Take over from the plant's state; `previous` is this effect's earlier term, if any."""

    def plate(self, nut, x_c):
        """Return the plate's compression (m) after the nut moved to `nut` (m) from plate x_c."""
        return nut

    def temperature(self, plant, dt):
        """Change `plant.temperature` over a step of `dt` s (the new geometry is set)."""

    def gas(self, plant, dt):
        """Change `plant.gas_amount` over a step of `dt` s."""

    def sensor(self, p, dt, t):
        """Return the reading (Pa) of the pressure `p` (Pa) at time `t` s, after a step of dt s."""
        return p

    @classmethod
    def hooks(cls):
        """Names of the hooks this term overrides."""
        return tuple(name for name in ('plate', 'temperature', 'gas', 'sensor')
                     if getattr(cls, name) is not getattr(PlantTerm, name))
