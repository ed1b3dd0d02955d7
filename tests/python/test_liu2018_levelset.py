"""Paper §3.3 with the blocks as YADE LevelSet bodies (examples/liu2018_blocks.py --blocks
levelset, paper §4.1), very coarse: dx 0.02 m, 1 point per cell (500 points, R_p0 12.4 mm),
level-set grid 2 mm, 602 boundary nodes, 0.25 s (about 1,000 steps, a few seconds)."""
import importlib.util
import math
import os

import numpy as np
import pytest

import mpmsdem
from yade import O
from yade.wrapper import LevelSet

G = 9.81
RHO_BLOCK, SIZE = 500.0, (0.020, 0.198, 0.018)  # Table 2: wooden blocks [kg/m^3], [m]
K_N = 1e4                                          # the example's YADE contact stiffness [N/m]


def script(name, folder):
    path = os.path.join(os.path.dirname(__file__), "..", "..", folder, name + ".py")
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def example():
    return script("liu2018_blocks", "examples")


@pytest.fixture(scope="module")
def run():
    L = example()
    a = L.parse(["--blocks", "levelset", "--dx", "0.02", "--ls-spacing", "0.002", "--ls-nodes", "602"])
    s = L.scene(0.02, 1, a, blocks=L.stackedBlocks(a.flow_friction, L.levelSetOf(a)), verbose=False)
    out = {"ids": list(s.blockIds), "shapes": [type(O.bodies[i].shape) for i in s.blockIds],
           "mass": [O.bodies[i].state.mass for i in s.blockIds],
           "levelSets": s.coupled.levelSetIds, "pos0": [O.bodies[i].state.pos for i in s.blockIds],
           "ori0": [O.bodies[i].state.ori for i in s.blockIds]}
    L.runCoupled(s, 0.25, sampleEvery=0.002)
    d = s.series(0)
    out.update(t=d["t"], F=d["Ft"], x=np.array([s.series(k)["travel"] for k in range(3)]).T,
               z=np.array(s.extra["z"]), contacts=np.array(s.extra["contacts"]),
               pos=[O.bodies[i].state.pos for i in s.blockIds], ori=[O.bodies[i].state.ori for i in s.blockIds],
               vel=[O.bodies[i].state.vel for i in s.blockIds], steps=O.iter)
    return out


def test_three_levelset_blocks_of_the_wooden_blocks_mass(run):
    """Three YADE LevelSet bodies, all coupled to the flow, each of the mass of a 20 x 198 x 18 mm
    block of 500 kg/m^3: 500 * 0.020 * 0.198 * 0.018 = 0.035640 kg. YADE integrates the mass
    over the level-set grid (0.035644 kg at h = 2 mm, +0.012 %); the bound is 0.1 %."""
    assert len(run["ids"]) == 3 and all(shape is LevelSet for shape in run["shapes"])
    assert run["levelSets"] == run["ids"]
    hand = RHO_BLOCK * SIZE[0] * SIZE[1] * SIZE[2]
    assert hand == pytest.approx(0.03564, rel=1e-12)
    for m in run["mass"]:
        assert m == pytest.approx(hand, rel=1e-3)


def test_the_glued_bottom_block_does_not_move(run):
    """blockedDOFs "xyzXYZ": position and orientation exactly those of the start, no velocity,
    although the flow pushes it (below)."""
    assert tuple(run["pos"][0]) == tuple(run["pos0"][0])
    assert (run["ori"][0] * run["ori0"][0].conjugate()).toAngleAxis()[0] == 0.0
    assert run["vel"][0].norm() == 0.0
    assert np.all(run["x"][:, 0] == 0.0) and np.all(run["z"][:, 0] == run["z"][0, 0])


def test_the_stack_holds_still_until_the_flow_arrives(run):
    """Before the flow first touches a block the upper blocks rest on linear springs k_n = 1e4 N/m
    at their equilibrium overlap (weight carried / k_n: W/k_n = 35 um for the top block, 70 um
    under the middle one). Started just touching instead, a block would fall through that overlap
    and swing about it by as much again; placed at equilibrium it must move by far less: the
    bound is half the top block's overlap, W/(2 k_n) = 17.5 um, vertically and along the flume
    (measured: 0.02 um vertically, 0 along the flume).
    The flow first touches the stack after 0.031 s at the earliest: the column front (x = 0.1 m)
    cannot run faster than the dam-break front of an inviscid fluid, 2 sqrt(g H_i) = 2.80 m/s
    (Ritter), and the points touch at their radius R_p0 = 12.4 mm, so the gap is
    0.1 - 0.0124 = 0.0876 m; it must arrive within the run (0.25 s; measured 0.204 s, 1,055
    steps in all)."""
    touched = np.nonzero(run["contacts"].sum(axis=1) > 0)[0]
    assert len(touched)
    first = touched[0]
    tTouch = run["t"][first]
    ritter = (0.1 - 0.0124) / (2 * math.sqrt(G * 0.2))
    assert ritter == pytest.approx(0.0313, abs=1e-4)
    assert ritter < tTouch < 0.25
    W = RHO_BLOCK * SIZE[0] * SIZE[1] * SIZE[2] * G
    bound = W / (2 * K_N)
    assert bound == pytest.approx(17.5e-6, rel=0.01)
    before = slice(0, first)
    assert np.abs(run["z"][before, 1:] - run["z"][0, 1:]).max() < bound
    assert np.abs(run["x"][before, 1:]).max() < bound


def test_the_flow_pushes_the_bottom_block_once_it_arrives(run):
    """No contact, no force: the flow's force on the bottom block is exactly zero until the front
    reaches it, and then pushes it downstream: the mean downstream force over the 20 ms after
    the first touch is > 0 (the flow moves downstream and the block cannot yield; measured
    56.5 N, an impact transient at this resolution, not a converged load)."""
    c, t, F = run["contacts"][:, 0], run["t"], run["F"]
    first = np.nonzero(c > 0)[0][0]
    assert np.all(F[:first] == 0.0)
    window = (t >= t[first]) & (t < t[first] + 0.02)
    assert F[window].mean() > 0.0


@pytest.mark.parametrize("tilt, axis", [(0.5, (1, 0, 0)), (10.0, (1, 1, 0))])
def test_a_dropped_levelset_block_keeps_its_energy_on_the_bed(tilt, axis):
    """The flume's YADE contact of a LevelSet block with the bed (linear spring k_n 1e4 N/m,
    Coulomb friction, no damping; scripts/validation/levelset_contact_energy.py): a block dropped
    from rest, tilted, bounces on its corners without sliding; over 1 s (1e4 steps) its energy
    stays within 1 % of the start (measured 1.000 and 1.000). Thrown sliding and spinning it
    gains energy (2.08 times in 1 s, docs/coupled-results.md "§4.1"): not asserted here."""
    probe = script("levelset_contact_energy", os.path.join("scripts", "validation"))
    assert 0.99 < probe.energyRatio(1e-4, tilt, axis, thrown=False) < 1.01


def test_a_stiff_levelset_contact_holds_the_step():
    """The coupled engine's step control does not see YADE's contacts of LevelSet blocks, so
    Flume holds O.dt (and the coupled engine's dtMax) below 0.3 sqrt(m/k_n) of the lightest free
    one: for a 20 mm cube of 500 kg/m^3 (4.00e-3 kg; YADE's integral over its 2 mm grid gives
    4.12e-3 kg, +3 %) on k_n = 1e6 N/m, 0.3 sqrt(4.12e-3/1e6) = 1.926e-5 s, under the flow's
    step at dx 0.02 m. Resting on the bed at its equilibrium
    overlap W/k_n = 39 nm, it must stay there: a spring released from touching swings by 2 W/k_n
    at most; unstable steps would throw it off the bed. 400 steps, before the flow arrives."""
    from mpmsdem.flume import Block, Flume
    L = example()
    cube = Block(half=(0.01,) * 3, x=0.3, density=RHO_BLOCK, friction=0.6, flowFriction=0.13,
                 levelSet={"spacing": 0.002, "nSurfNodes": 602})
    s = Flume(inclineDeg=0.0, length=0.6, width=0.2, columnLength=0.1, columnHeight=0.2, dx=0.02, ppc=1,
              granular=L.GRANULAR, basalFriction=0.13, blocks=[cube], verbose=False, dtAuto=0.5,
              levelSetContact={"kn": 1e6, "ks": 1e6 / 2.6})
    i = s.blockIds[0]
    m = O.bodies[i].state.mass
    assert m == pytest.approx(RHO_BLOCK * 0.02 ** 3, rel=0.05)
    assert s.levelSetStep == pytest.approx(0.3 * math.sqrt(m / 1e6), rel=1e-12)
    assert s.levelSetStep == pytest.approx(1.926e-5, rel=1e-3)
    assert s.coupled.dtMax == s.levelSetStep and O.dt <= s.levelSetStep
    z0 = O.bodies[i].state.pos[2]
    worst = 0.0
    for _ in range(40):
        mpmsdem.run(10, s.coupled)
        assert O.dt <= s.levelSetStep * (1 + 1e-12)
        worst = max(worst, abs(O.bodies[i].state.pos[2] - z0))
    assert s.coupled.contactCount(i) == 0  # the flow has not reached it
    assert worst < 2 * m * G / 1e6


def test_options_the_levelset_blocks_do_not_take_are_refused():
    """--backend cuda and --precision float (the LevelSet coupling runs on the double CPU solver),
    and a level-set grid coarser than the points' radius R_p0 = (3 dx^3 / (4 pi ppc))^(1/3)
    (6.2 mm at dx 0.01 m, 1 per cell; 3.1 mm at 8 per cell) are refused before anything runs."""
    L = example()
    for bad in (["--backend", "cuda"], ["--precision", "float"], ["--ls-spacing", "0"], ["--ls-nodes", "4"],
                ["--ls-kn", "-1"]):
        with pytest.raises(SystemExit):
            L.parse(["--blocks", "levelset"] + bad)
    rp = (3 * 0.01 ** 3 / (4 * math.pi)) ** (1 / 3)
    assert rp == pytest.approx(6.204e-3, rel=1e-3)
    with pytest.raises(ValueError, match="--ls-spacing"):
        L.settings(L.parse(["--blocks", "levelset", "--ls-spacing", "0.0063"]))
    assert L.settings(L.parse(["--blocks", "levelset", "--ls-spacing", "0.0062"]))[:2] == (0.01, 1)
    with pytest.raises(ValueError, match="--ls-spacing"):
        L.settings(L.parse(["--blocks", "levelset", "--full", "--ls-spacing", "0.0032"]))
    assert L.parse(["--backend", "cuda"]).blocks == "sdem"  # the SDEM path keeps its options
