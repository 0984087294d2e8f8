"""The effect demos (particles.demos.effects): data that makes physical sense."""

import numpy as np

from particles.collisions import Plane
from particles.demos import run_demo


def test_fountain_water_stays_above_the_ground():
    """The fountain's collider keeps every drop on or above the ground plane."""
    data = run_demo("fountain", seconds=2.0, fps=5)
    ground = Plane([0, 0, 0], [0, 0, 1])
    assert min(ground.H(x).min(initial=0.0) for x in data.positions) >= -1e-12
    assert max(len(x) for x in data.positions) > 300


def test_fireworks_sparks_come_from_rockets():
    """Hierarchy: bursts appear only after the first rocket has died, and outnumber the rockets."""
    data = run_demo("fireworks", seconds=2.5, fps=10)
    counts = [len(x) for x in data.positions]
    assert counts[0] == 0 and max(counts) > 100  # 140 +- 40 sparks per rocket


def test_smoke_rises_and_fades():
    """Gravity points up: the smoke's centre rises; old puffs are more transparent than young ones."""
    data = run_demo("smoke", seconds=2.0, fps=5)
    heights = [x[:, 1].mean() for x in data.positions if len(x)]
    assert heights[-1] > heights[1] > 0
    x, rgba = data.positions[-1], data.colors[-1]
    high = x[:, 1] > np.median(x[:, 1])
    assert rgba[high, 3].mean() < rgba[~high, 3].mean()
