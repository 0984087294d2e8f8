"""The bouncing balls demo (particles.demos.collisions): no ball inside the scenery."""

from particles.collisions import Box, Plane, Sphere
from particles.demos import run_demo


def test_bouncing_balls_stay_in_the_box_and_out_of_the_obstacles():
    """No ball is ever inside a wall, the ramp or the round obstacle."""
    data = run_demo("bouncing", seconds=2.0, fps=10)
    scene = Box([0.0, 0.0], [4.0, 3.0], container=True) | Sphere([2.2, 0.9], 0.45) | Plane([0.0, 0.8], [1.0, 2.0])
    assert min(scene.H(x).min() for x in data.positions) >= -1e-12
    assert data.info["contacts"] > 0
