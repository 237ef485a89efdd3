"""The shared test helpers fail where they should (tests/_helpers.py)."""

import numpy as np
import pytest
from _helpers import assert_same_characteristic_polynomial, assert_same_eigenvalues


def test_eigenvalue_sets_compare_independently_of_order() -> None:
    a = [-1 + 2j, -1 - 2j, -3.0]
    # a conjugate pair whose real parts differ by rounding, in any order, still matches
    b = [-3.0, -1 - 2j + 1e-14, -1 + 2j - 1e-14]
    assert_same_eigenvalues(a, b, rtol=1e-12)
    assert_same_characteristic_polynomial(a, b, rtol=1e-12, atol=1e-12)
    # sorting would pair them the wrong way round: the matching does not
    with pytest.raises(AssertionError):
        np.testing.assert_allclose(np.sort_complex(np.array(a)), np.sort_complex(np.array(b)))


@pytest.mark.parametrize(
    "b", [[-1 + 2j, -1 + 2j, -3.0], [-1 + 2j, -1 - 2j, -3.001], [-1 + 2j, -1 - 2j]]
)
def test_different_eigenvalue_sets_fail(b: list[complex]) -> None:
    a = [-1 + 2j, -1 - 2j, -3.0]
    with pytest.raises(AssertionError):
        assert_same_eigenvalues(a, b, rtol=1e-6)
    with pytest.raises(AssertionError):
        assert_same_characteristic_polynomial(a, b, rtol=1e-6, atol=1e-9)
