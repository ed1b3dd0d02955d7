"""scripts/validation/bed_height.py at its coarsest spacing (Δx 0.02 m, a few seconds): where a
layer at rest feels its bed.

For a column at rest ∂σ_zz/∂z = ρ g, so ∫ σ_zz dV = −g ∫ ρ (z − z_b) dV with z_b where the
bed's reaction enters (tension > 0): the stress field itself says where the bed acts."""
import os
import sys

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts", "validation"))
import bed_height as bh  # noqa: E402

DX = 0.02


@pytest.fixture(scope="module")
def layers():
    return {bed: bh.restLayer(DX, bed) for bed in ("wall", "terrain", "terrain-half", "sdem")}


def test_the_settled_layer_carries_its_weight_as_lithostatic_stress(layers):
    for bed, r in layers.items():
        assert r["settled"], bed
        # away from the bed and the top, -σ_zz falls at ρ g: 0.980-1.035 measured on the four beds
        assert 0.97 < r["slope_ratio"] < 1.045, bed
        # the layer does not sink into its bed: the top less the settled volume over the footprint is
        # where the points were seeded from (the slab's: R_p0 - Δx/4 = 0.060 Δx above it, less its
        # barrier's give); the effects below are a tenth of a cell and more
        seeded = r["rp"] - DX / 4 if bed == "sdem" else 0.0
        assert abs(r["mass_bed"] - seeded) < 0.02 * DX, bed


def test_a_terrain_on_the_node_layer_is_the_wall(layers):
    # a flat terrain removes the same velocity from the same nodes (those at or below it) as the wall
    for key in ("top", "virial_bed", "line_bed", "lowest_point"):
        assert layers["terrain"][key] == pytest.approx(layers["wall"][key], abs=1e-9)


def test_where_the_stress_field_puts_the_bed(layers):
    # the wall: just under its node layer, from the overload the two lowest point layers carry
    # (-0.130 to -0.132 dx measured at dx 0.02 to 0.005 m: a fixed fraction of the cell, so
    # millimetres that fall with it)
    assert -0.16 * DX < layers["wall"]["virial_bed"] < -0.10 * DX
    # a terrain half a cell above the node layer still acts on that node layer (the nodes at or
    # below it): the reaction enters half a cell under the terrain, not at it (-0.500 dx measured)
    assert -0.52 * DX < layers["terrain-half"]["virial_bed"] < -0.48 * DX
    # the slab pushes on the lowest points themselves (contact forces at the points, not the
    # grid): the bed is their centres' height, R_p0 (0.31 dx) above the slab less the barrier's give
    r = layers["sdem"]
    assert r["virial_bed"] == pytest.approx(r["lowest_point"], abs=0.01 * DX)
    assert 0.25 * DX < r["virial_bed"] < r["rp"]
