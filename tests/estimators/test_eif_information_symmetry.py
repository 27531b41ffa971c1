"""The EIF update keeps the information matrix exactly symmetric, as
:meth:`relloc.core.gaussian.InformationState.from_symmetric` (which it calls without checking)
requires: the next factorisation reads one triangle only."""

import numpy as np

from relloc.core.gaussian import Gaussian
from relloc.estimators.eif import TeamInformation, eif_update
from relloc.models.planar_measurement import LinearisedRows


def test_information_matrix_after_an_update_is_exactly_symmetric():
    rng = np.random.default_rng(0)
    n, m = 4, 12
    A = rng.normal(size=(3 * n, 3 * n))
    prior = TeamInformation.from_gaussian(Gaussian(rng.normal(size=3 * n), A @ A.T + np.eye(3 * n)))
    rows = LinearisedRows(
        residual=rng.normal(size=m),
        blocks=rng.normal(size=(m, 2, 3)),
        block_index=np.array([rng.choice(n, 2, replace=False) for _ in range(m)]),
        sigma=rng.uniform(0.05, 0.5, m),
        group=np.arange(m),
    )
    Y = eif_update(prior, rows).info.info_matrix
    np.testing.assert_array_equal(Y, Y.T)
