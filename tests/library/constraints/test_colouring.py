"""Graph colouring of constraints (particles.constraints.colouring): independent groups covering every row."""

import numpy as np

from particles.massspring import cloth
from particles.constraints import color_constraints


def test_groups_share_no_particle_and_cover_every_row():
    """Every colour group of pairs and triples is independent, and the groups cover each row once."""
    c = cloth(8, 8)
    for idx in (c.spring_indices(), np.stack([np.arange(40), np.arange(1, 41), np.arange(2, 42)], axis=1)):
        groups = color_constraints(idx, 64)
        assert np.array_equal(np.sort(np.concatenate(groups)), np.arange(len(idx)))
        for g in groups:
            used = idx[g].ravel()
            assert len(np.unique(used)) == len(used)
