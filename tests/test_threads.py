"""The compiled cycles on numba's threads: every thread count moves the blocks the same, bit for bit
(each contact writes its own sums, each block adds its contacts' in contact order), and the thread
count is set and checked like any other setting (drydem.engine.threads, ``--threads``)."""

import dataclasses

import click
import numpy as np
import pytest
from click.testing import CliRunner

import drydem as dd
from drydem.engine import cycle3d, cycle_planar, loop
from drydem.engine.damping import Damping
from drydem.engine.joints import kernel_joint
from drydem.engine import threads as kernel_threads
from drydem.engine.threads import available, get_threads, set_threads, threads_for, using_threads
from drydem.errors import DrydemError
from drydem.masonry.building import SMALL, building_model
from conftest import layout_blocks, tilted_gravity

#: 1 and 2 threads, and all of them where there are more
THREAD_COUNTS = sorted({1, min(2, available()), available()})


def two_course_building() -> dd.Model:
    """The small building's plan, two courses high, no openings: 3D (not held in y), 109 blocks,
    ~270 contacts, ~3,900 sub-contacts; the walls' soft joints (kn = ks = 3e7 Pa/m), so that the
    blocks move far enough in 10,000 cycles to need new contacts."""
    spec = dataclasses.replace(SMALL, storeys=1, storey_height_courses=2, windows_per_wall=0, sill_courses=0, window_height_courses=1,
                               door_height_courses=0)
    model = building_model(spec)
    return model.replace(joint=dd.JointMaterial(kn=3e7, ks=3e7, friction=model.joint.friction))


@pytest.fixture
def every_thread_busy(monkeypatch):
    """Models this small run on one thread (threads_for): here they take all they are given."""
    monkeypatch.setattr(kernel_threads, "SUBCONTACTS_PER_THREAD", 1)


def motion(model, threads, cycles, gravity, engine="numba"):
    """The state, sub-contact forces and the call's result after ``cycles`` undamped cycles on
    ``threads`` threads, from rest as drawn."""
    with using_threads(threads):
        sim = dd.Simulation(model, engine=engine, damping=Damping(0.0))
        result = sim.cycle(cycles, gravity=gravity)
    c = sim.contacts
    return (sim.state.position, sim.state.quaternion, sim.state.velocity, sim.state.angular_velocity, c.shear_force, c.normal_force,
            c.intact), result


def assert_bit_identical(runs):
    (first, result), *others = runs
    for arrays, other_result in others:
        assert other_result == result
        for a, b in zip(arrays, first):
            assert np.array_equal(a, b)


@pytest.mark.skipif(len(THREAD_COUNTS) < 2, reason="one core: nothing to compare")
def test_every_thread_count_moves_a_3d_building_the_same_bit_for_bit(every_thread_busy):
    """10,000 undamped cycles of a two-course building on a table tilted 15 deg, 30 deg out of its
    walls' planes: the blocks rock and slide in all six degrees of freedom (contacts re-detected
    on the way), and 1, 2 and all threads end in the same state, bit for bit."""
    model = two_course_building()
    assert not model.in_plane
    runs = [motion(model, n, 10_000, tilted_gravity(15.0, turn_deg=30.0)) for n in THREAD_COUNTS]
    (position, quaternion, velocity, omega, shear, *_), result = runs[0]
    assert result.detections > 0 and len(np.unique(shear[:, 0])) > 100
    assert np.abs(position - model.block_centroid).max() > 1e-3 and (np.abs(omega).max(axis=0) > 1e-3).all()
    assert_bit_identical(runs)


@pytest.mark.skipif(len(THREAD_COUNTS) < 2, reason="one core: nothing to compare")
def test_every_thread_count_moves_an_in_plane_wall_the_same_bit_for_bit(every_thread_busy):
    """The planar kernel: the built-in wall WD3 on a table tilted to 20 deg (collapsing, so contacts
    open, close and are re-detected), 10,000 cycles on 1, 2 and all threads."""
    from drydem.io.target import load_target

    model = load_target("WD3").model
    assert model.in_plane
    runs = [motion(model, n, 10_000, tilted_gravity(20.0)) for n in THREAD_COUNTS]
    (position, *_), result = runs[0]
    assert result.detections > 0 and np.abs(position - model.block_centroid).max() > 1e-3
    assert_bit_identical(runs)


@pytest.mark.parametrize("kernel", [cycle3d, cycle_planar], ids=["3d", "planar"])
def test_each_block_adds_its_contacts_forces_in_contact_order(kernel):
    """One step's block forces are the body force plus the contacts' sums scattered contact by contact
    (force[b] += F; force[a] -= F, in increasing contact order, as the serial kernel added them), bit
    for bit: in Python from the kernel's own per-contact sums."""
    model = two_course_building() if kernel is cycle3d else dd.build_model(_planar_blocks(), density=1800.0, supports=dd.Supports(fix_y=True))
    sim = dd.Simulation(model, engine="numba-3d" if kernel is cycle3d else "numba")
    sim.cycle(200, gravity=tilted_gravity(10.0, turn_deg=30.0 if kernel is cycle3d else 0.0))
    nb, state, sub = model.n_blocks, sim.state.copy(), sim.contacts.copy()
    width = cycle3d.CONTRIBUTION if kernel is cycle3d else cycle_planar.CONTRIBUTION
    work = loop.workspace(sub.pairs, nb, width)
    force, moment, rot = np.zeros((nb, 3)), np.zeros((nb, 3)), np.empty((nb, 3, 3))
    gravity = tilted_gravity(10.0)
    kernel.step(state, sim.blocks, sub, kernel_joint(model.joint), sim.closure_limit, gravity, sim.timestep, sim.timestep, Damping(0.0), rot,
                force, moment, False, work)
    expected = model.block_mass[:, None] * gravity
    if kernel is cycle_planar:
        expected[:, 1] = force[:, 1]  # the planar kernel leaves y alone
    for c, (a, b) in enumerate(sub.pairs.tolist()):
        q = work.contribution[c]
        if kernel is cycle3d:
            for k in range(3):
                expected[b, k] += q[k]
            for k in range(3):
                expected[a, k] -= q[k]
        else:
            expected[b, 0] += q[0]
            expected[b, 2] += q[1]
            expected[a, 0] -= q[0]
            expected[a, 2] -= q[1]
    assert len(sub.pairs) > 30 and np.array_equal(force, expected)


def _planar_blocks():
    """A small in-plane wall of the paper's bricks: four courses, running bond."""
    return layout_blocks("""
        bBBBb
        BBBB
        bBBBb
        BBBB
    """)


def test_block_incidence_lists_each_blocks_contacts_in_increasing_order():
    rng = np.random.default_rng(3)
    nb = 40
    pairs = np.array([rng.choice(nb - 2, 2, replace=False) for _ in range(300)], dtype=np.int64)  # blocks 38, 39 touch nothing
    start, entries = loop.block_incidence(pairs, nb)
    assert start[0] == 0 and start[-1] == 2 * len(pairs) and start[-1] == start[-3]
    for i in range(nb):
        codes = entries[start[i]:start[i + 1]]
        expected = [2 * c + side for c in range(len(pairs)) for side in (0, 1) if pairs[c, side] == i]
        assert codes.tolist() == expected
    empty = loop.block_incidence(np.zeros((0, 2), np.int64), 3)
    assert empty[0].tolist() == [0, 0, 0, 0] and len(empty[1]) == 0


def test_a_cycle_takes_a_thread_per_subcontacts_per_thread_up_to_the_setting():
    per = kernel_threads.SUBCONTACTS_PER_THREAD
    with using_threads(available()):
        assert threads_for(0) == threads_for(per - 1) == threads_for(2 * per - 1) == 1
        assert threads_for(2 * per) == min(2, available()) and threads_for(10**9) == available()
    with using_threads(1):
        assert threads_for(10**9) == 1


def test_set_threads_takes_a_count_from_one_to_all_cores_and_using_threads_restores_it():
    before = get_threads()
    with using_threads(1) as n:
        assert n == get_threads() == 1
        with using_threads(None) as n:
            assert n == get_threads() == available()
        assert get_threads() == 1
    assert get_threads() == before
    try:
        assert set_threads(1) == before and get_threads() == 1
    finally:
        set_threads(before)


@pytest.mark.parametrize("value", [0, -1, True, 1.0, 2.5, "2", available() + 1])
def test_set_threads_refuses_what_is_not_a_thread_count(value):
    before = get_threads()
    with pytest.raises(DrydemError, match=rf"threads = {value!r}: must be an integer in \[1, {available()}\]"):
        set_threads(value)
    assert get_threads() == before


def test_threads_option_sets_the_kernels_threads_or_says_what_is_allowed():
    from drydem.cli.common import threads_option

    seen = []

    @click.command()
    @threads_option
    def command():
        seen.append(get_threads())

    before = get_threads()
    runner = CliRunner()
    try:
        assert runner.invoke(command, ["--threads", "1"]).exit_code == 0
        assert runner.invoke(command, []).exit_code == 0
        assert seen == [1, available()]
        for bad in ("0", str(available() + 1), "two"):
            run = runner.invoke(command, ["--threads", bad])
            assert run.exit_code == 2 and "Traceback" not in run.output and "--threads" in run.output
            if bad != "two":
                assert f"must be an integer in [1, {available()}]" in run.output
        assert "Most threads for the compiled kernels (default: all cores;" in runner.invoke(command, ["--help"]).output
    finally:
        set_threads(before)
