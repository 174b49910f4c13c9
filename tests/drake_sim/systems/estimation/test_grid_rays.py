"""drake_sim.systems.estimation.grid_rays: the cells under a beam's half-cell samples, each once,
as the samples themselves say (a brute-force reference), off-grid points dropped."""

import math

import numpy as np

from drake_sim.systems.estimation import grid_rays as mut


def _reference(x, y, c, s, free_length, step, ox, oy, res, rows, cols):
    cells = set()
    for b in range(len(c)):
        k = 0
        while k * step < free_length[b]:
            t = k * step
            j = math.floor((x + c[b] * t - ox) / res)
            i = math.floor((y + s[b] * t - oy) / res)
            if 0 <= i < rows and 0 <= j < cols:
                cells.add(i * cols + j)
            k += 1
    return cells


def test_the_crossed_cells_are_the_samples_cells_each_once():
    rng = np.random.default_rng(3)
    angles = rng.uniform(-math.pi, math.pi, 200)
    lengths = np.concatenate([rng.uniform(-0.5, 6.0, 199), [0.0]])  # some none, one exactly 0
    c, s = np.cos(angles), np.sin(angles)
    rows, cols, res = 80, 100, 0.05  # 5 m x 4 m: long beams leave the grid
    seen = np.zeros(rows * cols, dtype=bool)
    args = (0.3, -0.2, c, s, lengths, 0.5 * res, -2.5, -2.0, res, rows, cols)
    cells = mut.crossed_cells(*args, seen)
    assert len(cells) == len(set(cells.tolist()))
    assert set(cells.tolist()) == _reference(*args)
    assert not seen.any()  # the scratch comes back clear
