import numpy as np
import pytest

from oceanloc.estimation.gaussian import Gaussian, clip_eigenvalues, symmetrize


def test_batch_construction_and_indexing():
    g = Gaussian.from_single([1.0, 2.0], np.eye(2), batch=3)
    assert g.batch_size == 3 and g.dim == 2
    assert g[1].batch_size == 1 and g[1:].batch_size == 2
    with pytest.raises(ValueError, match=r"\(B, n\)"):
        Gaussian(mean=np.zeros(2), cov=np.eye(2))


def test_eigenvalue_clipping_gives_nearest_psd():
    a = np.array([[2.0, 0.0], [0.0, -1.0]])
    fixed = clip_eigenvalues(a)
    w = np.linalg.eigvalsh(fixed)
    assert w.min() > 0 and w.min() < 1e-10
    assert fixed[0, 0] == pytest.approx(2.0)
    np.testing.assert_array_equal(symmetrize(np.array([[1.0, 2.0], [0.0, 1.0]])), [[1.0, 1.0], [1.0, 1.0]])
