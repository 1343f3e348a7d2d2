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
The doctor live (docs/doctor.md): model against measurement, rolling; a diagnosis off the thread.

A rolling comparison of model and measurement, and a diagnosis of the last window, in bounded
time, off the sample thread, when the residual leaves its floor.

The bridge between the two stacks (test_import_layers): the one module of the package through
which the online stack (the stiffness controller) reaches the offline one (the doctor). No ROS
here: the controller feeds samples and reports the numbers on /diagnostics.

- `RingBuffer`: the last samples (t, x_c, x_s, p, f: the actuator's columns, `table.COLUMNS`),
  preallocated; `append` is all the sample thread does (a lock and one column write).
- `ModelHealth`: the rolling comparison of a model with its measurement, for any set of outputs:
  a `residuals(rows)` function (measured minus model, per output) and a `floors(rows)` function
  (each output's noise floor). The first `calibration` seconds are taken as healthy: they give
  each output's noise floor, its residual offset (a model a little off is not a fault) and the
  largest RMS-over-floor ratio any `window` of it showed; the limit is `MARGIN` times that ratio,
  at least `LIMIT_MIN`. Every update, each output's RMS of (residual - offset) over the last
  `window` s, over its floor, is its ratio; the residual has left the floor when a ratio is above
  its limit `PERSIST` updates in a row. Nothing is taken from a device's nominal numbers.
  By default the actuator's: the residuals of paper B's model at the identified gas amount,
  measured pressure minus (17) at the measured (x_c, x_s), and measured spring force minus
  (7)-(12) on that pressure, over the doctor's noise floors (`actuator_causes.noise_floors`). A
  leak makes the pressure residual drift; a sensor lag makes it follow the rate; buckling shows
  in the force.
- `segment_health`: the arm's (the model node's): per segment, the external torque estimate
  τ_ext = M Ψ̈ + C Ψ̇ + N(Ψ) - τ_drive, A(2). The arm has no torque sensor: with no load on it
  the measured external torque is zero, so τ_ext is the residual (model error plus noise); a
  model gone wrong, a load, a leak in a chain drives it away from its healthy level. Its floor
  is `scoring.noise_floor_local` (the RMS about a 25-sample running mean), not the doctor's
  difference estimates: the driver differences Ψ̇ from the measured Ψ, so the friction term
  (5) flips sign from sample to sample and τ_ext's noise is far from white (first differences
  make it about twice its size); where the model holds M Ψ̈, Ψ̈ is a difference again.
- `SampleCost`: the sample thread's cost, per sample (`cost_us`).
- `diagnose_window`: the doctor (`diagnosis.diagnose`) on block means of the last window with the
  healthy window's noise floors, over the causes that develop in service (`live_causes`), from
  the model the residuals compare with (its own E_V and buckling in the baseline: `standing`).
- `DiagnosisWorker`: runs `diagnose_window` in a separate process (spawned: no fork of a process
  holding DDS threads; a process, not a thread, so the fit does not take the interpreter lock
  from the 1 kHz callback), one job at a time; a job over its time bound is killed, reported
  as timed out, and the process is restarted for the next.
- `LiveDoctor`: the three together, as the controller uses them.
"""
from collections import deque
import functools
import math
import multiprocessing
import threading
import time

import numpy as np

# The doctor's fits (diagnosis, actuator_causes: scipy.signal, over a second to import) are
# imported where they are first needed: the actuator's `ModelHealth` at its construction (the
# node's start, not its 1 Hz update), `diagnose_window` in the worker process. The model node,
# which needs neither, starts without them.
from bellows_ros.doctor.scoring import guarded_floor, noise_floor_local
from bellows_ros.io.table import COLUMNS as TABLE_COLUMNS
from bellows_ros.models.actuator import evaluate_array

COLUMNS = TABLE_COLUMNS['actuator'][0]   # t, x_c, x_s, p, f
OUTPUTS = ('p', 'f')
LIMIT_MIN = 3.0     # the limit of the RMS-over-floor ratio is never below this ...
MARGIN = 2.0        # ... nor below this times the largest ratio of the healthy window
PERSIST = 2         # updates in a row above the limit before the residual has left the floor
FIT_RATE = 50.0     # Hz of the block means the live diagnosis fits (leak and buckling are slow)
STARTUP_BOUND = 120.0   # s a worker process may take to start (imports) before it is given up
READY = 'ready'


class RingBuffer:
    """The last `capacity` samples of `columns`; `append` in O(1), copies in order."""

    def __init__(self, capacity, columns=COLUMNS):
        self.columns = tuple(columns)
        self.capacity = int(capacity)
        self._data = np.zeros((len(self.columns), self.capacity))
        self.count = 0                      # samples appended since the start
        self._lock = threading.Lock()

    def append(self, row):
        """One sample, its values in `columns` order."""
        with self._lock:
            self._data[:, self.count % self.capacity] = row
            self.count += 1

    def since(self, count):
        """Return ({column: array} of the samples appended after `count`, still held; count)."""
        with self._lock:
            end = self.count
            start = max(count, end - self.capacity, 0)
            index = np.arange(start, end) % self.capacity
            data = self._data[:, index]     # fancy indexing: a copy
        return dict(zip(self.columns, data)), end

    def last(self, n):
        """Return {column: array} of the last `n` samples (fewer if not yet held), a copy."""
        return self.since(self.count - int(n))[0]


def actuator_residuals(params, rows):
    """Return ({output: measured - model}) of paper B's model at its gas amount over `rows`."""
    p_model, f_model, _ = evaluate_array(params, rows['x_c'], rows['x_s'])
    return {'p': rows['p'] - p_model, 'f': rows['f'] - f_model}


def external_torques(names, rows):
    """Return {segment: τ_ext}: the residual itself, measured (zero, unloaded) minus model."""
    return {name: rows[name] for name in names}


def local_floors(names, rows):
    """
    Return {name: `scoring.noise_floor_local` of the column} (the module docstring says why).

    A noise-free column (simulated) gets a floor of 1e-6 of its span (`scoring.guarded_floor`), as
    the doctor's do.
    """
    return {name: guarded_floor(noise_floor_local(rows[name]), rows[name]) for name in names}


class ModelHealth:
    """
    The rolling comparison of model and measurement (module docstring).

    `outputs`: the residuals compared; `residuals(rows)` -> {output: array}, `floors(rows)` ->
    {output: noise floor} (both on {column: array}); by default the actuator's (paper B's model
    under `params`). `update(rows)` takes the new samples ({column: array}); `values()` the
    numbers to report. `state`: 'calibrating', 'healthy' or 'out of floor'.
    """

    def __init__(self, params=None, calibration=20.0, window=5.0, outputs=OUTPUTS,
                 residuals=None, floors=None):
        self.params = params
        self.outputs = tuple(outputs)
        self._residuals = residuals or functools.partial(actuator_residuals, params)
        if floors is None:
            from bellows_ros.doctor import actuator_causes     # module docstring: not at import
            floors = actuator_causes.noise_floors
        self._floors = floors
        self.calibration, self.window = float(calibration), float(window)
        self.floors = None                  # {output: noise floor} of the healthy window
        self.offsets = None                 # {output: mean residual} of the healthy window
        self.limits = None                  # {output: limit of the ratio}
        self.healthy_ratio = None           # {output: largest ratio of the healthy window}
        self.ratios = {name: math.nan for name in self.outputs}
        self.rms = {name: math.nan for name in self.outputs}
        self.mean = {name: math.nan for name in self.outputs}   # of (residual - offset)
        self.above = 0                      # updates in a row above the limit
        self._chunks = deque()              # (t, {output: residual}) chunks
        self._calibration_rows = []
        self.state = 'calibrating'

    @property
    def out_of_floor(self):
        return self.state == 'out of floor'

    def worst(self):
        """Return the output whose ratio is nearest its limit, or past it furthest."""
        return max(self.outputs, key=lambda n: self.ratios[n] / self.limits[n])

    def update(self, rows):
        """Take new samples; return the state."""
        if len(rows['t']) == 0:
            return self.state
        residual = self._residuals(rows)
        if self.floors is None:
            self._calibration_rows.append((rows, residual))
            t0 = self._calibration_rows[0][0]['t'][0]
            if rows['t'][-1] - t0 >= self.calibration:
                self._calibrate()
            return self.state
        self._chunks.append((rows['t'], residual))
        t_end = rows['t'][-1]
        while self._chunks and self._chunks[0][0][-1] < t_end - self.window:
            self._chunks.popleft()
        t = np.concatenate([c[0] for c in self._chunks])
        keep = t >= t_end - self.window
        for name in self.outputs:
            r = np.concatenate([c[1][name] for c in self._chunks])[keep] - self.offsets[name]
            self.rms[name] = float(np.sqrt(np.mean(r ** 2)))
            self.mean[name] = float(np.mean(r))
            self.ratios[name] = self.rms[name] / self.floors[name]
        over = any(self.ratios[n] > self.limits[n] for n in self.outputs)
        self.above = self.above + 1 if over else 0
        self.state = 'out of floor' if self.above >= PERSIST else 'healthy'
        return self.state

    def _calibrate(self):
        columns = self._calibration_rows[0][0].keys()
        rows = {c: np.concatenate([r[c] for r, _ in self._calibration_rows]) for c in columns}
        residual = {n: np.concatenate([e[n] for _, e in self._calibration_rows])
                    for n in self.outputs}
        self._calibration_rows = []
        self.floors = self._floors(rows)
        self.offsets = {n: float(np.mean(residual[n])) for n in self.outputs}
        t = rows['t']
        self.healthy_ratio, self.limits = {}, {}
        for name in self.outputs:
            centred = residual[name] - self.offsets[name]
            worst = 0.0
            for start in np.arange(t[0], t[-1] - self.window + 1e-9, self.window / 2):
                part = centred[(t >= start) & (t < start + self.window)]
                if len(part):
                    worst = max(worst, float(np.sqrt(np.mean(part ** 2))) / self.floors[name])
            self.healthy_ratio[name] = worst
            self.limits[name] = max(LIMIT_MIN, MARGIN * worst)
        self.state = 'healthy'

    def values(self):
        """{key: number} to report (nan before the healthy window is in)."""
        out = {'state': self.state, 'window_s': self.window, 'calibration_s': self.calibration}
        for name in self.outputs:
            out[f'residual_rms_{name}'] = self.rms[name]
            out[f'residual_mean_{name}'] = self.mean[name]
            out[f'noise_floor_{name}'] = (self.floors or {}).get(name, math.nan)
            out[f'ratio_{name}'] = self.ratios[name]
            out[f'limit_{name}'] = (self.limits or {}).get(name, math.nan)
        return out


def segment_health(names, calibration=20.0, window=5.0):
    """Return the `ModelHealth` of the arm's segments `names`: τ_ext over its noise floor."""
    names = tuple(names)
    return ModelHealth(None, calibration, window, outputs=names,
                       residuals=functools.partial(external_torques, names),
                       floors=functools.partial(local_floors, names))


class SampleCost:
    """
    The sample thread's cost: `add(seconds)` per sample; `take()` the numbers.

    `take()` returns (mean µs per sample, max µs of one sample) since the last `take`.
    """

    def __init__(self):
        self._s, self._n, self._max = 0.0, 0, 0.0

    def add(self, seconds):
        self._s += seconds
        self._n += 1
        if seconds > self._max:
            self._max = seconds

    def take(self):
        mean = self._s / self._n * 1e6 if self._n else math.nan
        worst = self._max * 1e6 if self._n else math.nan
        self._s, self._n, self._max = 0.0, 0, 0.0
        return mean, worst


def block_means(rows, factor):
    """Return block means of `factor` consecutive rows of every column (`Record.decimated`)."""
    n = len(rows['t']) // factor * factor
    return {name: np.asarray(column[:n], float).reshape(-1, factor).mean(axis=1)
            for name, column in rows.items()}


def live_causes():
    """Return the causes that develop while the actuator runs (each effect's `in_service`)."""
    from bellows_ros.models.actuator_effects import EFFECTS   # the doctor's imports: see above
    return tuple(effect.name for effect in EFFECTS if effect.in_service)


def diagnose_window(config, rows, floors, causes=None):
    """
    Return the doctor's verdict on one window: {'causes', 'values', 'seconds', 'error'}.

    `rows`: {column: array} at the full sample rate; `floors`: the healthy window's noise floors
    (the window itself is not healthy). Fitted on block means at `FIT_RATE` Hz. A window the
    doctor refuses (too short, the chamber never moves) gives the refusal as `error`.

    The baseline is the model the monitor compares with (`actuator_residuals`: the whole model):
    the model's own E_V and buckling stay in it (`actuator_causes.standing_physics`), so that the
    doctor names what changed, not the standing physics of the device. Without them the buckling
    fit, free over its physical range, took up the model's own buckling and E_V on a healthy
    window (#32). `causes`: default `live_causes()`; the others belong to the build and are the
    offline doctor's (`bellows diagnose`).
    """
    from bellows_ros.doctor import actuator_causes, diagnosis    # in the worker process
    started = time.perf_counter()
    dt = float(np.median(np.diff(rows['t'])))
    factor = max(1, int(round(1.0 / (dt * FIT_RATE))))
    try:
        result = diagnosis.diagnose('actuator', block_means(rows, factor), config,
                                    causes=causes or live_causes(), source='live window',
                                    raw_noise=floors, factor=factor,
                                    standing=actuator_causes.standing_physics(config.model))
    except Exception as exc:   # reported, not raised: a live window may be anything
        return {'causes': [], 'values': {}, 'seconds': time.perf_counter() - started,
                'error': f'{type(exc).__name__}: {exc}'}
    return {'causes': list(result.causes),
            'values': {c: dict(result.values[c]) for c in result.causes},
            'seconds': time.perf_counter() - started, 'error': None}


def _serve(connection):
    """Serve in the worker process: say it is ready, answer (job, function, args) until None."""
    from bellows_ros.identify.blas import one_blas_thread
    with one_blas_thread():    # faster fits (identify/blas.py), and the node keeps its core
        connection.send(READY)
        while True:
            try:
                request = connection.recv()
            except EOFError:        # the node is gone
                return
            if request is None:
                return
            job, function, args = request
            connection.send((job, function(*args)))


class DiagnosisWorker:
    """
    One diagnosis at a time in a spawned process, within `time_bound` s.

    `submit(function, *args)` -> False if one is running; `poll()` -> a finished result (the
    function's return value, or {'error': 'timed out ...'} after the bound), else None. The
    bound counts from the moment the process is ready: a fresh process first imports the doctor
    (`STARTUP_BOUND`).
    """

    def __init__(self, time_bound=30.0):
        self.time_bound = float(time_bound)
        self._context = multiprocessing.get_context('spawn')
        self._process = self._connection = None
        self._job, self._started = 0, None
        self._ready = False

    @property
    def busy(self):
        return self._started is not None

    def submit(self, function, *args):
        if self.busy:
            return False
        if self._process is None:
            self._connection, child = self._context.Pipe()
            self._process = self._context.Process(target=_serve, args=(child,), daemon=True,
                                                  name='live_doctor')
            self._process.start()
            child.close()
            self._ready = False
        self._job += 1
        self._connection.send((self._job, function, args))
        self._started = time.monotonic()
        return True

    def poll(self):
        if not self.busy:
            return None
        if not self._ready:
            if self._connection.poll() and self._connection.recv() == READY:
                self._ready, self._started = True, time.monotonic()
            elif time.monotonic() - self._started > STARTUP_BOUND:
                self._restart()
                return {'causes': [], 'values': {}, 'seconds': math.nan,
                        'error': f'worker did not start within {STARTUP_BOUND:g} s'}
            else:
                return None
        if self._connection.poll():
            try:
                job, result = self._connection.recv()
            except (EOFError, OSError) as exc:
                self._restart()
                return {'causes': [], 'values': {}, 'seconds': math.nan,
                        'error': f'worker lost: {type(exc).__name__}'}
            if job == self._job:
                self._started = None
                return result
        elapsed = time.monotonic() - self._started
        if elapsed > self.time_bound:
            self._restart()
            return {'causes': [], 'values': {}, 'seconds': elapsed,
                    'error': f'timed out after {self.time_bound:g} s'}
        return None

    def _restart(self):
        """Kill the process (the next `submit` starts another)."""
        self._started = None
        if self._process is not None:
            self._process.kill()
            self._process.join(5.0)
            self._connection.close()
        self._process = self._connection = None

    def close(self):
        if self._process is not None and not self.busy:
            try:
                self._connection.send(None)
            except OSError:
                pass
            self._process.join(2.0)
        if self._process is not None and self._process.is_alive():
            self._restart()
        self._process = self._connection = None


class LiveDoctor:
    """
    The rolling comparison, the ring buffer and the worker, as the controller uses them.

    `sample(t, x_c, x_s, p, f)` on the sample thread, one actuator sample (one message): a row
    into the ring buffer. One thread at a time (a node's callbacks in its default, mutually
    exclusive callback group). Its cost is counted (`cost_us`: `SampleCost`);
    `update()` from a timer: the new samples into `health`, a diagnosis of the last `diagnosis_s`
    seconds submitted when the residual has left the floor (again every `rediagnose_s` while it
    stays out), a finished one collected into `verdict`. `verdict` is cleared when the residual
    is back within its floor.
    """

    def __init__(self, config, calibration=20.0, window=5.0, diagnosis_s=20.0, time_bound=30.0,
                 rediagnose_s=30.0, rate=1000.0, worker=None):
        self.config = config
        self.health = ModelHealth(config.model, calibration, window)
        self.diagnosis_s, self.rediagnose_s = float(diagnosis_s), float(rediagnose_s)
        self.buffer = RingBuffer(int((max(calibration, diagnosis_s) + 2 * window) * rate))
        self.worker = worker or DiagnosisWorker(time_bound)
        self.verdict = None                 # the last finished diagnosis while out of floor
        self.diagnoses = 0
        self.out_since = None               # sample time the residual left the floor
        self._read = 0
        self._submitted_at = None
        self.cost = SampleCost()

    def sample(self, t, x_c, x_s, p, f):
        """Take one whole sample on the sample thread: a row into the ring buffer, counted."""
        start = time.perf_counter()
        self.buffer.append((t, x_c, x_s, p, f))
        self.cost.add(time.perf_counter() - start)

    def cost_us(self):
        """Return (mean µs per sample buffered, max µs of one call) since the last call."""
        return self.cost.take()

    def update(self):
        rows, self._read = self.buffer.since(self._read)
        state = self.health.update(rows)
        result = self.worker.poll()
        if result is not None:
            self.diagnoses += 1
            if self.health.out_of_floor:
                self.verdict = result
        if not self.health.out_of_floor:
            self.verdict = self.out_since = self._submitted_at = None
            return state
        now = time.monotonic()
        if self.out_since is None:
            self.out_since = float(rows['t'][-1]) if len(rows['t']) else math.nan
        due = self._submitted_at is None or now - self._submitted_at >= self.rediagnose_s
        if due and not self.worker.busy and self.health.floors is not None:
            window = self.buffer.last(int(self.diagnosis_s / self._dt()))
            order = np.argsort(window['t'], kind='stable')   # completed in any order
            window = {name: column[order] for name, column in window.items()}
            if self.worker.submit(diagnose_window, self.config, window, dict(self.health.floors)):
                self._submitted_at = now
        return state

    def _dt(self):
        rows = self.buffer.last(100)
        steps = np.diff(np.sort(rows['t']))
        return float(np.median(steps)) if len(steps) else 1e-3

    def close(self):
        self.worker.close()


def describe(verdict):
    """One line naming a verdict's causes with their fitted sizes (or why there is none)."""
    if verdict is None:
        return 'diagnosing'
    if verdict.get('error'):
        return f'no diagnosis: {verdict["error"]}'
    if not verdict['causes']:
        return 'no live cause explains it (' + ', '.join(live_causes()) + ' tried)'
    parts = []
    for cause in verdict['causes']:
        sizes = ', '.join(f'{k} {v:.3g}' for k, v in verdict['values'][cause].items())
        parts.append(f'{cause} ({sizes})')
    return ', '.join(parts)
