"""The damping-law table and the parameter schema, against values written out by hand."""

import ast
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import camdyn
from camdyn.errors import ParameterError, UnknownKeyError
from camdyn.model import layout as L
from camdyn.model.contact import contact_force, restitution_factor
from camdyn.model.equilibrium import viscous_coefficient
from camdyn.params import laws
from camdyn.params.config import (
    SCHEMA,
    build_system,
    load_system,
    read_table,
    system_from_toml,
    system_to_toml,
)
from camdyn.params.system import Cam, Contact, Follower, Friction, Motion, Spring, System
from camdyn.params.units import registry

# docs/model.md §3 and thesis 2.3.4, 3.2: the laws, their aliases (thesis letters) and kinds
NAMES = ["none", "viscous", "stiffness-proportional", "zhang-whiten", "stiffness-proportional-viscous",
         "zhang-whiten-viscous", "power", "hunt-crossley", "lankarani-nikravesh", "flores", "gonthier", "hu-guo"]
ALIASES = {"A": "viscous", "B": "stiffness-proportional", "C": "zhang-whiten",
           "D": "stiffness-proportional-viscous", "E": "zhang-whiten-viscous", "generalized": "power"}
RESTITUTION = {"hunt-crossley", "lankarani-nikravesh", "flores", "gonthier", "hu-guo"}
NEEDS_ZETA = {"viscous", "stiffness-proportional-viscous", "zhang-whiten-viscous"}  # laws A, D, E


def test_every_law_has_exactly_one_row():
    rows = laws.TABLE
    assert sorted(row.name for row in rows) == sorted(NAMES)
    assert len({row.code for row in rows}) == len(rows)
    assert {row.name for row in rows if row.restitution is not None} == RESTITUTION
    assert {row.name for row in rows if row.needs_damping_ratio} == NEEDS_ZETA
    for name in NAMES:
        assert laws.lookup(name).name == name
        assert Contact(damping=name, restitution=0.5).damping == name
    for alias, name in ALIASES.items():
        assert laws.lookup(alias).name == name
        assert Contact(damping=alias).damping == name  # an alias is replaced by the name
    assert {alias for row in rows for alias in row.aliases} == set(ALIASES)


def test_unknown_law_is_refused_with_the_list():
    with pytest.raises(ParameterError, match="hunt-crossley"):
        Contact(damping="hunt-crosley")
    with pytest.raises(ParameterError, match="contact.damping"):
        load_system("sundar2014-impact", {"contact.damping": "magic"})


# what beta multiplies in the damping coefficient c of F_d = c delta_dot (docs/model.md §3):
# B and D: c = beta F_k [N]; C and E: c = beta delta^0.25; power: c = beta delta^n
BETA_TIMES = {"stiffness-proportional": lambda n: "N", "stiffness-proportional-viscous": lambda n: "N",
              "zhang-whiten": lambda n: "m**0.25", "zhang-whiten-viscous": lambda n: "m**0.25",
              "power": lambda n: f"m**{n}" if n else ""}  # (pint refuses m**0.0)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("exponent", [0.0, 0.25, 1.0, 1.5, 2.7])
def test_beta_unit_gives_a_force(name, exponent):
    ureg = registry()
    row = laws.lookup(name)
    assert row.uses_beta == (name in BETA_TIMES)
    beta = ureg.Quantity(1.0, row.unit_of_beta(exponent))
    times = BETA_TIMES.get(name, lambda n: "")(exponent)  # other laws: beta is read as c itself
    force = beta * ureg.Quantity(1.0, times) * ureg.Quantity(1.0, "m/s")
    assert force.dimensionality == ureg.newton.dimensionality
    assert force.to("N").magnitude == pytest.approx(1.0)


def test_beta_is_read_in_the_unit_of_its_law():
    s = load_system("sundar2014-impact", {"contact.damping": "B", "contact.beta": "3.25 s/m"})
    assert s.contact.beta == pytest.approx(3.25)
    s = load_system("sundar2014-impact", {"contact.damping": "C", "contact.beta": "2 kN*s/m^1.25"})
    assert s.contact.beta == pytest.approx(2e3)
    s = load_system("sundar2014-impact", {"contact.exponent": "1.0", "contact.beta": "20 kN*s/m^2"})
    assert s.contact.beta == pytest.approx(2e4)


# chi(e) at e = 0.8 and e = 0.5, worked out by hand from the references' formulas
FACTORS = {
    "hunt-crossley": (3 * 0.2 / 2, 3 * 0.5 / 2),                    # 3 (1 - e) / 2
    "lankarani-nikravesh": (3 * (1 - 0.64) / 4, 3 * 0.75 / 4),      # 3 (1 - e^2) / 4
    "flores": (8 * 0.2 / (5 * 0.8), 8 * 0.5 / (5 * 0.5)),           # 8 (1 - e) / (5 e)
    "gonthier": ((1 - 0.64) / 0.8, 0.75 / 0.5),                     # (1 - e^2) / e
    "hu-guo": (3 * 0.2 / (2 * 0.8), 3 * 0.5 / (2 * 0.5)),           # 3 (1 - e) / (2 e)
}


@pytest.mark.parametrize("name", sorted(FACTORS))
def test_restitution_relation_matches_the_reference(name):
    row = laws.lookup(name)
    assert row.reference.startswith("doi:10.")
    for e, expected in zip((0.8, 0.5), FACTORS[name]):
        assert row.restitution(e) == pytest.approx(expected, rel=1e-14)
        assert restitution_factor(name, e) == pytest.approx(expected, rel=1e-14)


@pytest.mark.parametrize("name", sorted(FACTORS))
def test_compiled_force_uses_the_restitution_factor(impact_rig, name):
    s = impact_rig.with_values(**{"contact.damping": name, "contact.restitution": 0.8, "contact.beta": 0.0})
    p = L.pack(s)
    rho_c, delta, delta_dot, approach = 0.0175, 2e-6, 0.03, 0.4
    estar = 210e9 / (2 * (1 - 0.3 ** 2))                      # two steels, eq 3.12
    rho_e = 1 / (1 / rho_c + 1 / s.follower.pin_radius)      # eq 4.18
    elastic = 4 / 3 * estar * math.sqrt(rho_e) * delta ** 1.5
    fn, fk = contact_force(delta, delta_dot, rho_c, approach, p)
    assert fk == pytest.approx(elastic, rel=1e-12)
    assert fn - fk == pytest.approx(FACTORS[name][0] * elastic * delta_dot / approach, rel=1e-9)


def test_restitution_bounds():
    Contact(damping="hunt-crossley", restitution=0.0)  # the factor does not divide by e
    with pytest.raises(ParameterError, match="restitution"):
        Contact(damping="flores", restitution=0.0)
    with pytest.raises(ParameterError, match="restitution"):
        Contact(damping="gonthier", restitution=1.2)


def test_only_laws_a_d_e_need_the_damping_ratio(friction_rig):
    for name in NAMES:
        s = friction_rig.with_values(**{"contact.damping": name, "contact.damping_ratio": 0.1,
                                        "contact.restitution": 0.8})
        c = viscous_coefficient(s)
        assert (c > 0.0) == (name in NEEDS_ZETA), name


# the keys of the configuration format (docs/model.md, camdyn presets keys)
KEYS = """cam.radius cam.semi_major cam.semi_minor cam.runout cam.pivot_x cam.pivot_y cam.youngs_modulus
cam.poisson_ratio follower.mass follower.inertia follower.cg_distance follower.length follower.width
follower.pin_radius follower.youngs_modulus follower.poisson_ratio follower.accelerometer_distance
spring.stiffness spring.free_length spring.attachment_x spring.ground_depth spring.tilt contact.kind
contact.length contact.damping contact.damping_ratio contact.beta contact.exponent contact.restitution
contact.reference_velocity contact.clip_adhesion friction.law friction.coefficient friction.smoothing
motion.kind motion.speed motion.amplitude motion.frequency motion.initial_angle motion.direction
motion.zero_state motion.start_speed motion.ramp_time environment.gravity""".split()


def test_schema_keys_and_units():
    assert sorted(SCHEMA) == sorted(KEYS)
    assert SCHEMA["follower.inertia"][0] == "kg*m**2"
    assert SCHEMA["contact.beta"][0] == "law"
    assert SCHEMA["motion.speed"][0] == "speed"
    assert SCHEMA["environment.gravity"][0] == "m/s**2"
    assert all(meaning for _, meaning in SCHEMA.values())


def test_written_toml_has_the_format_of_the_presets(impact_rig):
    text = system_to_toml(impact_rig)
    assert '[cam]\nradius = "0.0175 m"\nrunout = "0.0035 m"\n' in text
    assert 'inertia = "0.0033 kg*m^2"' in text
    assert 'damping = "power"\ndamping_ratio = 0.0\nexponent = 1.5\nbeta = "24700000000.0 N*s/m**2.5"' in text
    assert 'speed = "16.0 Hz"' in text and "initial_angle" not in text
    assert text.endswith('[environment]\ngravity = "9.81 m/s^2"\n')


@pytest.mark.parametrize("key, suggestion", [
    ("cam.runoot", "cam.runout"), ("cam.raduis", "cam.radius"), ("follower.mas", "follower.mass"),
    ("contact.dampnig", "contact.damping"), ("motion.zero_stat", "motion.zero_state"),
    ("environment.gravty", "environment.gravity"), ("spring.stifness", "spring.stiffness"),
])
def test_misspelled_keys_are_refused_with_a_suggestion(key, suggestion):
    with pytest.raises(UnknownKeyError, match=f"did you mean .*{suggestion}"):
        load_system("sundar2014-impact", {key: "1"})
    values = read_table("sundar2014-impact")[0]  # as if the key were in the file
    with pytest.raises(UnknownKeyError, match=f"did you mean .*{suggestion}"):
        build_system({**values, key: "1"})


def test_missing_parameter_is_named():
    with pytest.raises(ParameterError, match="missing parameter 'cam.runout'"):
        build_system({"cam.radius": "10 mm"})


finite = dict(allow_nan=False, allow_infinity=False)
text = st.text(st.characters(blacklist_categories=("Cs",)), max_size=20)


@st.composite
def systems(draw):
    """Any valid system: every law, kind and option, with arbitrary floats in valid ranges."""
    a = draw(st.floats(2e-3, 0.1, **finite))
    b = a if draw(st.booleans()) else a * draw(st.floats(0.3, 1.0, **finite))
    cam = Cam(semi_major=a, semi_minor=b, runout=b * draw(st.floats(0.0, 0.95, **finite)),
              pivot_x=draw(st.floats(0.05, 0.3, **finite)), pivot_y=draw(st.floats(-0.3, 0.3, **finite)),
              youngs_modulus=draw(st.floats(1e6, 1e12, **finite)), poisson_ratio=draw(st.floats(-0.99, 0.49)))
    mass, length = draw(st.floats(1e-3, 10.0, **finite)), draw(st.floats(0.01, 1.0, **finite))
    cg = length * draw(st.floats(0.0, 1.0, **finite))
    follower = Follower(mass=mass, inertia=mass * cg ** 2 + draw(st.floats(1e-6, 1.0, **finite)),
                        cg_distance=cg, length=length, width=draw(st.floats(1e-3, 0.02, **finite)),
                        pin_radius=draw(st.floats(0.0, 0.005, **finite)),
                        youngs_modulus=draw(st.floats(1e6, 1e12, **finite)),
                        poisson_ratio=draw(st.floats(-0.99, 0.49)),
                        accelerometer_distance=draw(st.floats(0.0, 1.0, **finite)))
    spring = Spring(stiffness=draw(st.floats(0.0, 1e6, **finite)), free_length=draw(st.floats(0.0, 0.2, **finite)),
                    attachment_x=draw(st.floats(0.0, 0.5, **finite)),
                    ground_depth=draw(st.floats(-0.2, 0.2, **finite)), tilt=draw(st.floats(-0.78, 0.78)))
    kind = draw(st.sampled_from(["point", "line"]))
    contact = Contact(kind=kind, length=draw(st.floats(1e-4, 0.1, **finite)) if kind == "line" else 0.0,
                      damping=draw(st.sampled_from(NAMES + list(ALIASES))),
                      damping_ratio=draw(st.floats(0.0, 2.0, **finite)), beta=draw(st.floats(0.0, 1e12, **finite)),
                      exponent=draw(st.floats(0.0, 3.0, **finite)), restitution=draw(st.floats(1e-3, 1.0)),
                      reference_velocity=draw(st.floats(1e-6, 10.0, **finite)), clip_adhesion=draw(st.booleans()))
    friction = Friction(law=draw(st.sampled_from(["none", "coulomb", "tanh"])),
                        coefficient=draw(st.floats(0.0, 1.0, **finite)), smoothing=draw(st.floats(1e-3, 1e3, **finite)))
    oscillating = draw(st.booleans())
    swing = st.floats(1e-3, 3.0, **finite) if oscillating else st.floats(0.0, 3.0, **finite)
    motion = Motion(kind="oscillating" if oscillating else "constant", speed=draw(st.floats(0.0, 200.0, **finite)),
                    amplitude=draw(swing), frequency=draw(swing), direction=draw(st.sampled_from([1, -1])),
                    zero_state=draw(st.sampled_from(["auto", "maximum-lift", "runout-parallel"])),
                    initial_angle=draw(st.none() | st.floats(-10.0, 10.0, **finite)))
    return System(cam=cam, follower=follower, spring=spring, contact=contact, friction=friction, motion=motion,
                  gravity=draw(st.floats(0.0, 30.0, **finite)), name=draw(text), citation=draw(text))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(system=systems())
def test_any_valid_system_reads_back_equal(system):
    again = system_from_toml(system_to_toml(system))
    assert again == system
    assert np.array_equal(L.pack(again), L.pack(system))


def test_no_private_name_is_imported_across_modules():
    src = Path(camdyn.__file__).parent
    for path in src.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("camdyn"):
                private = [a.name for a in node.names if a.name.startswith("_") and not a.name.startswith("__")]
                assert not private, f"{path.relative_to(src)} imports {private} from {node.module}"
