"""Tribology (Hertz, film thickness, lambda ratio), the Benedict-Kelley fit, and modal
damping by half power."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from camdyn.errors import IdentificationError, PresetError
from camdyn.identification.modal import (
    accelerance,
    half_power_damping,
    synthesize_impulse_test,
)
from camdyn.model.layout import effective_modulus
from camdyn.tribology import (
    contact_conditions,
    fit_benedict_kelley,
    hamrock_dowson_film,
    lambda_ratio,
    load_lubricant,
    lubrication_regime,
    normalized_friction,
    roughness_preset,
)
from camdyn.tribology.benedict_kelley import benedict_kelley

A = 17.5e-3


def test_hertz_contact_closed_form(friction_rig):
    """Point contact: a^3 = 3 F rho_e / (4 E*) and p0 = 3 F / (2 pi a^2) (Johnson, Contact
    Mechanics, eq 4.22), written here independently of camdyn's delta-based form."""
    system = friction_rig.with_values(**{"cam.runout": 0.116 * A})
    cc = contact_conditions(system, 11.55)
    fn = cc["Fn"].values
    rho_e = 1 / (1 / cc["cam_curvature_radius"].values + 1 / system.follower.pin_radius)
    a = (3 * fn * rho_e / (4 * effective_modulus(system))) ** (1 / 3)
    np.testing.assert_allclose(cc["contact_radius"].values, a, rtol=1e-10)
    np.testing.assert_allclose(cc["peak_pressure"].values, 3 * fn / (2 * np.pi * a ** 2), rtol=1e-10)
    assert 0.8e9 < cc["peak_pressure"].values.mean() < 1.6e9     # about 1 GPa for steel pins


@settings(max_examples=30, deadline=None)
@given(scale=st.floats(1.5, 10.0))
def test_hamrock_dowson_exponents(scale):
    """The film scales as u^0.68, eta^0.68, w^-0.073 (Hamrock and Dowson 1977)."""
    lub = load_lubricant("agma-4ep")
    base = hamrock_dowson_film(5.0, 0.6, 0.0175, 0.0032, 2.2e11, lub)
    assert hamrock_dowson_film(5.0, 0.6 * scale, 0.0175, 0.0032, 2.2e11, lub) == pytest.approx(base * scale ** 0.68)
    assert hamrock_dowson_film(5.0 * scale, 0.6, 0.0175, 0.0032, 2.2e11, lub) == pytest.approx(base * scale ** -0.073)


def test_film_against_hand_computation():
    """One point computed by hand from the published formula: w = 5 N, u = 0.635 m/s,
    Rx = 17.5 mm, Ry = 3.2 mm, E' = 219.8 GPa, eta = 0.034 Pa s, alpha = 20e-9 m^2/N:
    U = 5.613e-12, G = 4396, W = 7.419e-8, k = 0.3510, H = 3.63 U^.68 G^.49 W^-.073
    (1 - e^-0.68k) = 3.45e-6, h = 60.4 nm."""
    h = hamrock_dowson_film(5.0, 0.635, 0.0175, 0.0032, 219.78e9, load_lubricant("agma-4ep"))
    assert float(h) == pytest.approx(60.4e-9, rel=0.01)


def test_lambda_and_regimes():
    rc, rb = roughness_preset("ground")
    assert (rc, rb) == pytest.approx((0.29e-6, 0.25e-6))
    assert lambda_ratio(math.hypot(rc, rb) * 2.0, rc, rb) == pytest.approx(2.0)
    assert list(lubrication_regime([0.5, 2.0, 4.0])) == ["boundary", "mixed", "EHL"]
    with pytest.raises(PresetError, match="unknown lubricant"):
        load_lubricant("castor-oil")


def test_contact_conditions_with_lubricant(friction_rig):
    system = friction_rig.with_values(**{"cam.runout": 0.116 * A})
    agma = contact_conditions(system, 11.55, "agma-4ep", "ground")
    iso = contact_conditions(system, 11.55, "iso-32", "ground")
    # the thicker oil gives the thicker film, by (eta ratio)^0.68 (alpha ratio)^0.49
    ratio = (0.034 / 0.012) ** 0.68 * (20 / 18) ** 0.49
    np.testing.assert_allclose(agma["film_thickness"].values / iso["film_thickness"].values, ratio, rtol=1e-10)
    assert set(np.unique(agma["regime"].values)) <= {"boundary", "mixed", "EHL"}


def test_benedict_kelley_round_trip():
    """Synthetic (Rm, mu) from the thesis's AGMA 4EP constants, 1 % noise: C1 and C2 back."""
    rng = np.random.default_rng(4)
    c1, c2 = 0.0288e-6, 2.03e-6
    rm = np.linspace(0.25e-6, 0.65e-6, 12)
    term = 10.0 + rng.uniform(-0.5, 0.5, rm.size)
    mu = benedict_kelley(rm, term, c1, c2) * (1 + 0.01 * rng.standard_normal(rm.size))
    fit = fit_benedict_kelley(rm, mu, term)
    assert fit.c1 == pytest.approx(c1, rel=0.1)
    assert fit.c2 == pytest.approx(c2, rel=0.1)
    assert fit.rms_error < 0.02 * mu.mean()
    # fig 4.9: the normalized friction rises with roughness
    assert np.all(np.diff(normalized_friction(rm, fit.c1, fit.c2)) > 0)
    with pytest.raises(IdentificationError, match="at least three"):
        fit_benedict_kelley(rm[:2], mu[:2], term[:2])


@pytest.mark.parametrize("zeta", [0.01, 0.02, 0.03, 0.05])
def test_half_power_recovers_damping(zeta):
    """zeta within 3 % on the synthetic two-mass impulse test, 1 % noise."""
    rec = synthesize_impulse_test(damping_ratios=(zeta, 0.02), noise=0.01, seed=2)
    f1, f2 = rec.attrs["natural_frequencies"]
    freq, h = accelerance(rec)
    est = half_power_damping(freq, h, (0.5 * f1, 0.5 * (f1 + f2)))
    assert est.damping_ratio == pytest.approx(zeta, rel=0.03)
    assert est.natural_frequency == pytest.approx(f1, rel=0.01)


def test_unresolved_or_leaking_peaks_refused():
    rec = synthesize_impulse_test(damping_ratios=(0.01, 0.02), duration=0.05)   # 2.7 decay times
    with pytest.raises(IdentificationError, match="not decayed"):
        accelerance(rec)
    rec = synthesize_impulse_test(damping_ratios=(0.05, 0.02), duration=0.04)
    freq, h = accelerance(rec)
    with pytest.raises(IdentificationError, match="not resolved"):
        half_power_damping(freq, h, (500, 1400))
