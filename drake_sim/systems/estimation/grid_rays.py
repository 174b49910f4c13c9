"""The cells a scan's beams cross on a ``LogOddsGrid``, as one compiled numba kernel (cached on
disk): what ``LogOddsGrid.insert_scan`` clears. The same points as the array version it
replaced (every half cell along each beam, ``t = k * step`` while ``t`` is short of the
beam's free length, the same float operations), without building them all at once: a 50 m
SICK beam on a 2.5 cm grid is 4,000 points, a scan 1.4 million.
"""

import math

import numba
import numpy as np


@numba.njit(cache=True)
def crossed_cells(x, y, c, s, free_length, step, origin_x, origin_y, resolution, rows, cols, seen):
    """Flat indices (``i * cols + j``), each once, of the cells under the points ``(x + c[b] *
    t, y + s[b] * t)`` for ``t = k * step < free_length[b]``, k = 0, 1, ...; points off the
    grid are dropped. ``seen``: (rows * cols,) booleans, all False, returned so."""
    capacity = 0
    for b in range(len(c)):
        if free_length[b] > 0.0:
            capacity += int(math.ceil(free_length[b] / step)) + 1
    out = np.empty(capacity, dtype=np.int64)
    count = 0
    for b in range(len(c)):
        k = 0
        while True:
            t = k * step
            if not t < free_length[b]:
                break
            j = int(math.floor((x + c[b] * t - origin_x) / resolution))
            i = int(math.floor((y + s[b] * t - origin_y) / resolution))
            if 0 <= i < rows and 0 <= j < cols:
                flat = i * cols + j
                if not seen[flat]:
                    seen[flat] = True
                    out[count] = flat
                    count += 1
            k += 1
    for m in range(count):
        seen[out[m]] = False
    return out[:count]
