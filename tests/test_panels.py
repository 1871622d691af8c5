"""The graded panel integral (thetasol.core.panels) and the Taylor tables of a Fourier series
(thetasol.core.periodic.TaylorTable) against mpmath."""
import mpmath as mp
import numpy as np
import pytest

from thetasol.core.panels import PeriodicIntegral
from thetasol.core.periodic import TaylorTable


@pytest.mark.parametrize("g", [1e-2, 1e-6])
def test_periodic_integral_near_singular(g):
    """f = 1 / sqrt(g + sin^2(x/2)), singular at x = +-2i asinh(sqrt g): the period integral is
    4 K(1 / (1 + g)) / sqrt(1 + g) (mpmath.ellipk, 30 digits), the running integral is mpmath.quad's,
    and the inverse returns the points.  Measured (10 and 24 panels): 3.0e-15 relative (total and
    running), 8.4e-15 (F(F^-1(y)) - y), 2.8e-16 (F^-1(F(x)) - x, relative to 2 pi).  The panels are
    accurate to ~1e-16 each; what is left is the integrand's own rounding near x = 2 pi, where x is known
    to eps 2 pi absolute: ~eps / sqrt(g) relative there (4e-12 in the total at g = 1e-12)."""
    mp.mp.dps = 30
    F = PeriodicIntegral(lambda x: 1.0 / np.sqrt(g + np.sin(0.5 * x) ** 2),
                         [2j * np.arcsinh(np.sqrt(g)), -2j * np.arcsinh(np.sqrt(g))])
    total = 4 * mp.ellipk(1 / (1 + mp.mpf(g))) / mp.sqrt(1 + mp.mpf(g))
    assert abs(F.total - float(total)) <= 1e-14 * float(total)
    x = np.array([1e-7, 0.01, 1.0, 3.0, 6.2, 7.5, -2.0])
    exact = []
    for xx in x:
        turns = int(np.floor(xx / (2 * np.pi)))
        r = mp.mpf(float(xx)) - 2 * mp.pi * turns
        part = mp.quad(lambda s: 1 / mp.sqrt(g + mp.sin(s / 2) ** 2), [0, min(r, mp.mpf(1e-3)), r])
        exact.append(float(turns * total + part))
    assert np.all(np.abs(F(x) - exact) <= 1e-14 * float(total))
    y = np.linspace(-0.3, 1.7, 41) * F.total
    assert np.all(np.abs(F(F.inverse(y)) - y) <= 3e-14 * F.total)
    assert np.all(np.abs(F.inverse(F(x)) - x) <= 2e-15 * 2 * np.pi)


def test_taylor_table_against_mpmath():
    """Re(c_0 + 2 sum c_n e^{inx}) with c_n = 0.97^n e^{in/3} (300 terms) and its derivative at 25
    points: measured 1.1e-14 of sum |c| (value: x up to 20 is reduced modulo the float 2 pi, a relative
    change of x of order eps, times n x) and 3.6e-15 of sum n |c| (derivative)."""
    mp.mp.dps = 30
    n = np.arange(300)
    c = 0.97 ** n * np.exp(1j * n / 3)
    T = TaylorTable(c)
    x = np.random.default_rng(3).uniform(-7.0, 20.0, 25)
    g, dg = T(x)
    cm = [mp.mpc(complex(z)) for z in c]
    for xx, gg, dd in zip(x, g, dg, strict=True):
        xm = mp.mpf(float(xx))
        val = mp.re(cm[0] + 2 * mp.fsum(cm[k] * mp.expj(k * xm) for k in range(1, 300)))
        der = mp.re(2 * mp.fsum(1j * k * cm[k] * mp.expj(k * xm) for k in range(1, 300)))
        assert abs(gg - float(val)) <= 4e-14 * np.abs(c).sum()
        assert abs(dd - float(der)) <= 1e-14 * (n * np.abs(c)).sum()


def test_adaptive_series_refuses_with_its_own_exception():
    """A series whose tail stays large raises core's SeriesNotConverged (the solution layer turns it
    into ClosedFormUnavailable), not a bare NotImplementedError."""
    from thetasol.core.periodic import SeriesNotConverged, adaptive_series

    with pytest.raises(SeriesNotConverged, match="tail 1.0e"):
        adaptive_series(lambda n: np.ones(n), 128, "no decay (tail {tail:.1e})")
