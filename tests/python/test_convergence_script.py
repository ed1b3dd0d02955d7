"""scripts/validation/flume_convergence.py: its extrapolation to Δx 0 on exact power laws."""
import os
import sys

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts", "validation"))
import flume_convergence as fc  # noqa: E402


@pytest.mark.parametrize("p, h", [(2.0, (0.02, 0.01, 0.005)), (1.5, (0.02, 0.01, 0.2 / 28)),
                                  (0.8, (0.01, 0.2 / 28, 0.005))])
def test_richardson_recovers_an_exact_power_law(p, h):
    # f = 0.3 - 4 h^p, the spacings of the refinement runs (a ratio of 2, or 2 then 1.4)
    order, limit = fc.richardson([0.3 - 4 * x ** p for x in h], list(h))
    assert order == pytest.approx(p, abs=1e-9) and limit == pytest.approx(0.3, abs=1e-12)


def test_richardson_refuses_what_no_power_law_fits():
    h = [0.02, 0.01, 0.005]
    assert fc.richardson([1.0, 2.0, 1.0], h) is None      # the differences change sign
    assert fc.richardson([1.0, 1.0, 2.0], h) is None      # a zero difference
    assert fc.richardson([1.0, 1.1, 1.3], h) is None      # growing steps: not converging
