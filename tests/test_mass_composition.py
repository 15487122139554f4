"""Mass properties composed from the parts (savant_cli/vehicle/composition.py): the
parallel-axis theorem against hand-computed stacks, against an independent tensor
formulation, and against the ares_i generator's own whole-configuration sums; then a
vehicle file whose configurations give no mass table, composed from its parts' tables.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest
from omegaconf import OmegaConf

from savant_cli.datagen import ares_i_tables as gen
from savant_cli.errors import ConfigError
from savant_cli.paths import shipped_config_dir
from savant_cli.vehicle import load_vehicle
from savant_cli.vehicle.composition import combine, composed_table, full_row
from savant_cli.vehicle.tables import MassTable, inertia_tensors

SHIPPED = shipped_config_dir() / "vehicle"


def test_two_point_masses_on_the_axis():
    """Iyy = Izz = μ L² with the reduced mass μ = m₁m₂/(m₁+m₂); no roll inertia."""
    m1, m2, x1, x2 = 3.0e4, 1.0e4, 10.0, 50.0
    mass, cg, inertia = combine(np.array([m1, m2]), np.array([[x1, 0, 0], [x2, 0, 0]]), np.zeros((2, 6)))
    mu = m1 * m2 / (m1 + m2)
    assert mass == m1 + m2
    np.testing.assert_allclose(cg, [(m1 * x1 + m2 * x2) / (m1 + m2), 0.0, 0.0], rtol=1e-15)
    np.testing.assert_allclose(inertia, [0.0, mu * 40.0**2, mu * 40.0**2, 0.0, 0.0, 0.0], rtol=1e-12, atol=1e-6)


def test_an_offset_mass_gives_the_product_of_inertia_its_sign():
    """m₁ at the origin, m₂ at structure (L, h, 0): body offsets (−L, h, 0), so
    Ixx = μh², Iyy = μL², Izz = μ(L² + h²) and the product Ixy = Σ m x_b y_b = −μLh."""
    m1, m2, length, h = 2.0e3, 5.0e2, 4.0, 1.5
    _, cg, inertia = combine(np.array([m1, m2]), np.array([[0, 0, 0], [length, h, 0]]), np.zeros((2, 6)))
    mu = m1 * m2 / (m1 + m2)
    np.testing.assert_allclose(cg, [m2 * length / (m1 + m2), m2 * h / (m1 + m2), 0.0], rtol=1e-15)
    np.testing.assert_allclose(inertia, [mu * h * h, mu * length**2, mu * (length**2 + h * h), -mu * length * h, 0, 0],
                               rtol=1e-12, atol=1e-9)


def test_two_halves_of_a_cylinder_are_the_cylinder():
    """A solid cylinder (M, L, R): Ixx = MR²/2, Iyy = Izz = M(R²/4 + L²/12), from its two
    halves about their own CGs."""
    big_m, length, r = 8.0e4, 30.0, 2.5
    m = big_m / 2.0
    half = [m * r * r / 2.0, m * (r * r / 4.0 + (length / 2.0) ** 2 / 12.0)]
    own = np.array([[half[0], half[1], half[1], 0, 0, 0]] * 2)
    mass, cg, inertia = combine(np.array([m, m]), np.array([[20.0 - length / 4.0, 0, 0], [20.0 + length / 4.0, 0, 0]]),
                                own)
    whole = big_m * (r * r / 4.0 + length**2 / 12.0)
    np.testing.assert_allclose(inertia, [big_m * r * r / 2.0, whole, whole, 0, 0, 0], rtol=1e-13, atol=1e-6)
    np.testing.assert_allclose(cg, [20.0, 0.0, 0.0])


def test_the_tensor_form_of_the_theorem():
    """Random bodies: the tensor sum Σ [T_i + m_i(|d|²E − d dᵀ)] (d in body axes) in
    table form (products = −off-diagonal elements)."""
    rng = np.random.default_rng(7)
    n = 5
    masses = rng.uniform(10.0, 1000.0, n)
    cgs = rng.uniform(-5.0, 5.0, (n, 3))
    a = rng.normal(size=(n, 3, 3))
    tensors = a @ a.transpose(0, 2, 1) + 3.0 * np.eye(3)  # symmetric positive definite
    own = np.column_stack([tensors[:, 0, 0], tensors[:, 1, 1], tensors[:, 2, 2],
                           -tensors[:, 0, 1], -tensors[:, 0, 2], -tensors[:, 1, 2]])
    np.testing.assert_allclose(inertia_tensors(own), tensors)
    mass, cg, inertia = combine(masses, cgs, own)
    total = np.zeros((3, 3))
    for mi, ci, ti in zip(masses, cgs, tensors):
        d = np.diag([-1.0, 1.0, -1.0]) @ (ci - cg)
        total += ti + mi * (d @ d * np.eye(3) - np.outer(d, d))
    np.testing.assert_allclose(inertia_tensors(inertia[None, :])[0], total, rtol=1e-12)


def _table(rows: np.ndarray) -> MassTable:
    return MassTable(rows[:, 0], rows[:, 1], np.ascontiguousarray(rows[:, 2:5]), np.ascontiguousarray(rows[:, 5:]))


def test_the_parts_of_ares_i_compose_to_its_configurations():
    """The generator sums every segment of a configuration at once; composing the sums of
    its parts (each stage against its own propellant, the LES) must give the same tables."""
    first, upper_stage = (_table(gen.stage_mass_table(s)) for s in gen.STAGES)
    m, cg, inertia = gen.les_mass_properties()
    les = (m, np.array([cg, 0.0, 0.0]), inertia)
    composed = {"stack": composed_table(first, [full_row(upper_stage), les]),
                "upper_les": composed_table(upper_stage, [les]), "upper": composed_table(upper_stage, [])}
    for name, table in composed.items():
        rows = gen.mass_table(name)
        np.testing.assert_allclose(table.mass_kg, rows[:, 1], rtol=1e-13, err_msg=name)
        np.testing.assert_allclose(table.cg_m, rows[:, 2:5], rtol=1e-13, atol=1e-12, err_msg=name)
        np.testing.assert_allclose(table.inertia_kgm2, rows[:, 5:], rtol=1e-11, atol=1e-3, err_msg=name)


@pytest.fixture
def composed_folder():
    """ares_i's shipped folder (its stages' own mass tables beside the configurations'),
    and its YAML with the configurations' mass tables left out: composed."""
    node = OmegaConf.to_container(OmegaConf.load(SHIPPED / "ares_i.yaml").vehicle, resolve=True)
    for c in node["configurations"].values():
        del c["mass_table"]
    return SHIPPED / "ares_i", node


def test_a_vehicle_composed_from_its_parts_loads_its_configurations(composed_folder):
    folder, node = composed_folder
    composed = load_vehicle(node, folder)  # the LES's CG and inertia as the YAML gives them (9 digits)
    shipped = load_vehicle(OmegaConf.load(SHIPPED / "ares_i.yaml").vehicle, SHIPPED / "ares_i")
    for name, c in composed.configurations.items():
        ref = shipped.configurations[name].mass
        np.testing.assert_array_equal(c.mass.propellant_kg, ref.propellant_kg)
        np.testing.assert_allclose(c.mass.mass_kg, ref.mass_kg, rtol=1e-9, err_msg=name)  # the CSVs' 10 digits
        np.testing.assert_allclose(c.mass.cg_m, ref.cg_m, rtol=1e-9, atol=1e-9, err_msg=name)
        np.testing.assert_allclose(c.mass.inertia_kgm2, ref.inertia_kgm2, rtol=1e-8, atol=1e-2, err_msg=name)
    assert composed.tree.configurations["stack"].mass_file.endswith("(composed from its parts)")


def test_composition_needs_every_parts_mass(composed_folder):
    folder, node = composed_folder
    bad = copy.deepcopy(node)
    del bad["items"]["les"]["cg_m"]
    with pytest.raises(ConfigError, match="cg_m") as info:
        load_vehicle(bad, folder)
    assert info.value.key == "vehicle.items.les"
    bad = copy.deepcopy(node)
    del bad["stages"]["upper_stage"]["mass_table"]
    with pytest.raises(ConfigError, match="mass_table") as info:
        load_vehicle(bad, folder)
    assert info.value.key == "vehicle.stages.upper_stage"
    bad = copy.deepcopy(node)
    bad["stages"]["first_stage"]["tanks"]["grain"]["propellant_kg"] -= 10.0
    with pytest.raises(ConfigError, match="first_stage.mass_table") as info:
        load_vehicle(bad, folder)
    assert info.value.key == "vehicle.stages.first_stage.tanks.grain.propellant_kg"


def test_a_stage_heavier_than_its_declared_inert_mass_is_refused(composed_folder):
    """Composed tables agree with each other by construction; the first stage's own
    table at burnout must still be the inert mass the separation drops."""
    folder, node = composed_folder
    node["stages"]["first_stage"]["inert_mass_kg"] += 50.0
    with pytest.raises(ConfigError) as info:
        load_vehicle(node, folder)
    assert info.value.key == "vehicle.stages.first_stage.inert_mass_kg"
