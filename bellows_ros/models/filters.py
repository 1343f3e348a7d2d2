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
Vectorised dynamic operators the candidate causes are built from (pure functions on arrays).

- `lag`: first-order low pass (a sensor with time constant tau), first-order-hold discretisation,
  via `scipy.signal.lfilter`.
- `relax`: the response of a first-order relaxation to the increments of a driving signal
  (temperature after a compression, relaxing to ambient with a time constant).
- `play`: the backlash (play) operator of width `width`, computed as a prefix scan of clamps so
  that it needs log2(n) NumPy passes instead of a Python loop over samples.
- `reversals`: how often a signal reverses by more than a threshold (a zig-zag count).
"""
import numpy as np


def lag(x, dt, tau):
    """
    Low-pass: y' = (x - y) / tau with y(0) = x(0), sampled every dt.

    First-order-hold discretisation (x linear between samples): exact for ramps, and right for
    block-averaged records, whose samples are the moving average of the signal at the block
    centres; the zero-order hold would add a delay of dt/2 that a coarse fitting rate cannot
    afford.
    """
    x = np.asarray(x, float)
    if tau <= 0:
        return x.copy()
    a = np.exp(-dt / tau)
    c = tau / dt * (1.0 - a)
    b0, b1 = 1.0 - c, c - a
    from scipy.signal import lfilter   # here: the plants import the effects, not their fits
    y, _ = lfilter([b0, b1], [1.0, -a], x, zi=[(1.0 - b0) * x[0]])
    return y


def relax(x, dt, tau):
    """
    High-pass: z' = x' - z / tau with z(0) = 0, the part of the change of x not yet relaxed.

    A step of x by h gives z = h exp(-t / tau): the adiabatic jump and its decay.
    """
    x = np.asarray(x, float)
    a = np.exp(-dt / tau) if tau > 0 else 0.0
    increments = np.diff(x, prepend=x[0])
    from scipy.signal import lfilter
    return lfilter([1.0], [1.0, -a], increments)


def play(x, width, start=None):
    """
    Backlash: the output follows x only when x pushes it from one side of a gap of `width`.

    y_k = clamp(y_{k-1}, x_k - width/2, x_k + width/2), y_{-1} = `start` (default x_0). A
    composition of clamps is a clamp, so the recursion is a prefix scan over (low, high) pairs.
    """
    x = np.asarray(x, float)
    half = 0.5 * max(width, 0.0)
    low, high = x - half, x + half
    shift = 1
    n = len(x)
    while shift < n:
        # Compose clamp_k ∘ clamp_{k-shift}: the earlier bounds clamped into the later ones.
        new_low = np.clip(low[:-shift], low[shift:], high[shift:])
        new_high = np.clip(high[:-shift], low[shift:], high[shift:])
        low[shift:], high[shift:] = new_low, new_high
        shift *= 2
    y0 = x[0] if start is None else start
    return np.clip(y0, low, high)


def recurrence(a, b, x0):
    """
    Run x_0 = x0, x_{k+1} = a_k x_k + b_k (a time-varying first-order system).

    E.g. the gas amount of a leaking chamber. Closed form x_k = A_k (x0 + Σ_{j<k} b_j / A_{j+1}),
    A_k = Π_{j<k} a_j, evaluated in chunks short enough that A stays within exp(±30).
    """
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    n = len(a)
    log_a = np.log(np.clip(a, 1e-300, None))
    step = max(2, min(n, int(30.0 / max(float(np.max(np.abs(log_a))), 1e-12))))
    x = np.empty(n)
    start = float(x0)
    for lo in range(0, n, step):
        hi = min(n, lo + step)
        log_gain = np.concatenate(([0.0], np.cumsum(log_a[lo:hi - 1])))
        inputs = np.concatenate(([0.0], np.cumsum(b[lo:hi - 1] * np.exp(-log_gain[1:]))))
        x[lo:hi] = np.exp(log_gain) * (start + inputs)
        start = a[hi - 1] * x[hi - 1] + b[hi - 1]
    return x


def reversals(signal, threshold):
    """
    Count the direction reversals of `signal` by more than `threshold`.

    A zig-zag count that ignores noise smaller than the threshold.
    """
    count, direction = 0, 0
    high = low = float(signal[0])
    for value in np.asarray(signal, float).tolist():
        if direction == 0:
            high, low = max(high, value), min(low, value)
            if high - value > threshold:
                direction, low = -1, value
            elif value - low > threshold:
                direction, high = 1, value
        elif direction > 0:
            if value > high:
                high = value
            elif high - value > threshold:
                direction, low, count = -1, value, count + 1
        else:
            if value < low:
                low = value
            elif value - low > threshold:
                direction, high, count = 1, value, count + 1
    return count
