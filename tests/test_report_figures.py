"""The figures an engineer reads at a glance (drydem.report.plots), checked on their artists:
the pushover curve names the Eurocode 8 drift levels by what they are for, with the angle each
is reached at, and marks where blocks were lost; the mechanism draws lost blocks faded, every
panel on one colour scale, its legend off the blocks; a limit-analysis mechanism is labelled as
virtual displacements. Built from synthetic results and states, not from analyses."""

import numpy as np
import pytest

import drydem as dd
from conftest import layout_blocks
from drydem.analysis.drift import EC8_DRIFT_MEANINGS
from drydem.analysis.limit import LimitResult
from drydem.analysis.tilt import TiltResult, TiltSettings
from drydem.analysis.tilt.settings import Record
from drydem.masonry.building import BuildingSpec, building_model
from drydem.model.parameters import JointMaterial
from drydem.model.state import State
from drydem.report.plots import LOST_STYLE, limit_mechanism_drawing, mechanism_drawing, pushover_drawing

#: the wall height of the synthetic pushover curves, m
HEIGHT_M = 0.1


def tilt_result(ux_mm_per_deg: float, *, last_deg: int = 10, lost=(), jump_at_deg: float | None = None) -> TiltResult:
    """A made-up tilting result: equilibria at 0, 1, ... ``last_deg`` deg, the monitored point
    moving ``ux_mm_per_deg`` mm a degree (plus 5 mm from ``jump_at_deg`` on), collapse one
    degree past the last; ``lost``: (block, tilt in deg)."""
    records = []
    for tilt in range(last_deg + 1):
        ux_m = 1e-3 * (ux_mm_per_deg * tilt + (5.0 if jump_at_deg is not None and tilt >= jump_at_deg else 0.0))
        records.append(Record(float(tilt), ux_m, 0.0, ux_m / HEIGHT_M, 100))
    return TiltResult(settings=TiltSettings(), monitored_block="top", wall_height_m=HEIGHT_M, stable_under_gravity=True,
                      last_equilibrium_deg=float(last_deg), collapse_angle_deg=float(last_deg), records=records, lost_blocks=list(lost),
                      cycles=0, runtime_s=0.0, collapse_state=None, final_state=None, ended_by="monitored block fell")


def texts(fig) -> list[str]:
    """Every text of a figure: its axes' texts and annotations and its legends' entries."""
    found = [t.get_text() for ax in fig.axes for t in ax.texts]
    return found + [t.get_text() for legend in fig.legends for t in legend.get_texts()]


def test_the_pushover_names_each_ec8_drift_level_and_the_angle_it_is_reached_at():
    # 0.2 mm/deg on a 0.1 m wall: drift 0.2 %/deg, so 0.5 % at 2.5 deg, 0.75 % at 3.75 deg and
    # 1 % at 5 deg (linear interpolation between the states, drydem.analysis.drift)
    shown = texts(pushover_drawing(tilt_result(0.2)))
    assert f"drift 0.5 %, {EC8_DRIFT_MEANINGS[0.005]}: reached at 2.50 deg" in shown
    assert f"drift 0.75 %, {EC8_DRIFT_MEANINGS[0.0075]}: reached at 3.75 deg" in shown
    assert f"drift 1 %, {EC8_DRIFT_MEANINGS[0.01]}: reached at 5.00 deg" in shown
    assert {"0.5 %: 2.50 deg", "0.75 %: 3.75 deg", "1 %: 5.00 deg"} <= set(shown)  # beside the points on the curve
    # EN 1998-1 4.4.3.2 (1) a) to c): what each limit is for
    assert "brittle" in EC8_DRIFT_MEANINGS[0.005] and "ductile" in EC8_DRIFT_MEANINGS[0.0075]
    assert "not interfering" in EC8_DRIFT_MEANINGS[0.01] and "DLS" in EC8_DRIFT_MEANINGS[0.01]


def test_a_drift_level_the_curve_never_reaches_is_said_not_reached():
    # 0.08 mm/deg up to 10 deg: 0.8 mm, a drift of 0.8 %: 1 % is never reached
    shown = texts(pushover_drawing(tilt_result(0.08)))
    assert f"drift 1 %, {EC8_DRIFT_MEANINGS[0.01]}: not reached" in shown
    assert f"drift 0.75 %, {EC8_DRIFT_MEANINGS[0.0075]}: reached at 9.38 deg" in shown  # 0.75 / 0.08 = 9.375
    assert not any(text.startswith("1 %:") for text in shown)


def test_the_pushover_marks_the_tilts_where_blocks_were_lost():
    # two blocks fell at 6 deg (the curve jumps 5 mm there), one in the collapse step at 11 deg
    result = tilt_result(0.2, lost=[("a", 6.0), ("b", 6.0), ("c", 11.0)], jump_at_deg=6)
    fig = pushover_drawing(result)
    ax = fig.axes[0]
    markers = {line.get_label(): (line.get_xdata()[0], line.get_ydata()[0]) for line in ax.lines if line.get_gid() == "lost blocks"}
    assert markers == {"2 blocks lost at 6.00 deg": (pytest.approx(6.2), 6.0),  # on the state at 6 deg: 1.2 + 5 mm
                       "1 block lost at 11.00 deg (past the last equilibrium)": (pytest.approx(7.0), 11.0)}  # beside the curve's end
    jump = next(line for line in ax.lines if line.get_label().startswith("jump where blocks fell"))
    assert list(jump.get_xdata()[:2]) == pytest.approx([1.0, 6.2]) and list(jump.get_ydata()[:2]) == [5.0, 6.0]
    assert {"2 blocks lost at 6.00 deg", "1 block lost at 11.00 deg (past the last equilibrium)"} <= set(texts(fig))


def test_many_tilts_of_lost_blocks_share_one_label_past_the_first_three():
    lost = [(f"b{k}", float(k)) for k in range(1, 7)]
    labels = [line.get_label() for line in pushover_drawing(tilt_result(0.2, lost=lost)).axes[0].lines if line.get_gid() == "lost blocks"]
    assert len(labels) == 6
    assert [label for label in labels if not label.startswith("_")] == [
        "1 block lost at 1.00 deg", "1 block lost at 2.00 deg", "1 block lost at 3.00 deg", "3 more blocks lost at 4.00 to 6.00 deg"]


@pytest.fixture(scope="module")
def wall():
    """A 3.5-brick running-bond wall of 6 courses (top course c5: c5b0 to c5b3, left to right) on a base."""
    return dd.build_model(layout_blocks("bBBb\nBBB\n" * 3), density=1800.0, joint=dd.JointMaterial(kn=1e8, ks=1e8, friction=0.5),
                          supports=dd.Supports(fix_y=True))


def moved(model, shift_m, blocks=None) -> State:
    """``model`` at rest with ``blocks`` (default: every movable one) shifted by ``shift_m`` (x, y, z)."""
    position = model.block_centroid.copy()
    chosen = model.block_movable if blocks is None else np.isin(model.block_name, list(blocks))
    position[chosen] += shift_m
    return State.at_rest(position)


def coloured(ax):
    """The collection of an axes coloured by value (the blocks still in the model)."""
    return next(c for c in ax.collections if c.get_array() is not None)


def test_the_mechanism_draws_lost_blocks_faded_and_every_panel_on_one_scale(wall):
    lost = frozenset({"c5b0", "c5b1"})
    fallen = moved(wall, (0.004, 0.0, 0.0))
    fallen.position[np.isin(wall.block_name, list(lost))] += (0.01, 0.0, -0.02)
    fig = mechanism_drawing(wall, [("last equilibrium", moved(wall, (0.0005, 0.0, 0.0)), frozenset()), ("past collapse", fallen, lost)],
                            monitored="c5b3")
    equilibrium, collapse = (ax for ax in fig.axes if ax.get_label() != "<colorbar>")
    faded = [c for c in collapse.collections if c.get_label() == LOST_STYLE["label"]]
    assert len(faded) == 1 and faded[0].get_alpha() < 1 and len(faded[0].get_paths()) == len(lost)
    assert len(coloured(collapse).get_paths()) == wall.n_blocks - len(lost)
    assert not [c for c in equilibrium.collections if c.get_label() == LOST_STYLE["label"]]  # none lost by then
    assert coloured(equilibrium).norm is coloured(collapse).norm
    # the scale ends at the largest displacement of both panels' blocks in the model: 4 mm past
    # collapse (the lost blocks, uncoloured, do not count), and starts a thousandth of it below
    assert (coloured(collapse).norm.vmin, coloured(collapse).norm.vmax) == pytest.approx((0.004, 4.0))
    assert sum(ax.get_label() == "<colorbar>" for ax in fig.axes) == 1
    assert LOST_STYLE["label"] in texts(fig)


def test_the_mechanism_legend_covers_no_monitored_block(wall):
    # the top right block, under the old legend's place (upper right)
    states = [("last equilibrium", moved(wall, (0.0005, 0.0, 0.0)), frozenset()), ("past collapse", moved(wall, (0.01, 0.0, 0.0)), frozenset())]
    fig = mechanism_drawing(wall, states, monitored="c5b3")
    fig.canvas.draw()
    legend = fig.legends[0].get_window_extent()
    outlines = [p for ax in fig.axes for p in ax.patches if p.get_label() == "monitored: c5b3"]
    assert len(outlines) == 2 and "monitored: c5b3" in texts(fig)
    assert not any(legend.overlaps(p.get_window_extent()) for p in outlines)
    assert not any(legend.overlaps(ax.get_window_extent()) for ax in fig.axes)  # below the panels, on no block


def test_the_limit_mechanism_is_labelled_as_virtual_displacements(wall):
    # the top course sliding at 1 m/s, the course below at 0.5 m/s: a shape, no magnitude
    velocity = np.zeros((wall.n_blocks, 3))
    velocity[[name.startswith("c5") for name in wall.block_name], 0] = 1.0
    velocity[[name.startswith("c4") for name in wall.block_name], 0] = 0.5
    result = LimitResult(load_multiplier=0.5, method="associative", status="made up", iterations=1, converged=True, history=[0.5],
                         velocity=velocity, angular_velocity=np.zeros_like(velocity), normal_force=np.zeros(0))
    fig = limit_mechanism_drawing(wall, result, title="LA-A mechanism")
    bar = next(ax for ax in fig.axes if ax.get_label() == "<colorbar>")
    assert "virtual displacement" in bar.get_ylabel() and "mm" not in bar.get_ylabel()
    panel = next(ax for ax in fig.axes if ax.get_label() != "<colorbar>")
    assert sorted(set(coloured(panel).get_array())) == [0.0, 0.5, 1.0]


def test_a_building_mechanism_draws_lost_blocks_faded_on_one_scale_with_the_legend_off_the_panels():
    tiny = building_model(BuildingSpec(length_m=0.8, width_m=0.5, storeys=1, storey_height_courses=4, brick_length_m=0.1,
                                       brick_height_m=0.05, windows_per_wall=1, window_width_bricks=1, window_height_courses=1,
                                       sill_courses=1), joint=JointMaterial())
    *top, monitored = [tiny.block_name[b] for b in np.argsort(-tiny.block_centroid[:, 2])[:4]]  # in the top course
    lost = frozenset(top)
    states = [("last equilibrium", moved(tiny, (0.0, 0.001, 0.0)), frozenset()), ("past collapse", moved(tiny, (0.0, 0.05, 0.0)), lost)]
    fig = mechanism_drawing(tiny, states, monitored=monitored, load_direction=1)
    panels = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert all(ax.name == "3d" for ax in panels) and len(panels) == 2
    faded = [c for c in panels[1].collections if c.get_label() == LOST_STYLE["label"]]
    assert len(faded) == 1 and faded[0].get_alpha() < 1
    assert coloured(panels[0]).norm is coloured(panels[1]).norm
    fig.canvas.draw()
    legend = fig.legends[0].get_window_extent()
    assert f"monitored: {monitored}" in texts(fig) and LOST_STYLE["label"] in texts(fig)
    assert not any(legend.overlaps(ax.get_window_extent()) for ax in panels)


def test_a_log_axis_reads_its_powers_of_ten_while_a_dollar_in_a_name_stays_text(tmp_path):
    """Found by a hunt: plain_text turned off mathtext in the tick labels of the report's kn
    axes too, which then read $\\mathdefault{10^{8}}$; a $ in a name is still no formula."""
    from drydem.report.plots import new_figure, saved

    fig = new_figure()
    ax = fig.add_subplot()
    ax.plot([3e7, 1e8, 1e9], [1.0, 0.8, 0.6], label="a$^$b")
    ax.set(xscale="log", title="wall a$^$b")
    ax.legend()
    saved(fig, tmp_path / "log.png")
    labels = [label for label in ax.get_xticklabels() if label.get_text()]
    assert labels and all(label.get_parse_math() for label in labels)
    assert "$\\mathdefault{10^{8}}$" in [label.get_text() for label in labels]
    assert not ax.title.get_parse_math() and not ax.get_legend().get_texts()[0].get_parse_math()


def test_a_histogram_of_angles_on_the_tilt_s_steps_centres_a_bar_on_each_step():
    """Found by a hunt: with numpy's "auto" bins the edges fell on 21.5, ... deg, so nine
    samples at 21.5 deg were drawn in the [21.5, 22.0) bar and one at 23.5 in [23.0, 23.5]."""
    from drydem.report.plots import histogram_bins

    angles = np.array([21.5] * 9 + [22.0, 23.5])
    edges = histogram_bins(angles)
    counts, _ = np.histogram(angles, edges)
    centres = (edges[:-1] + edges[1:]) / 2
    assert np.allclose(centres, [21.5, 22.0, 22.5, 23.0, 23.5]) and counts.tolist() == [9, 1, 0, 0, 1]
    assert histogram_bins(np.array([20.0, 20.3, 21.7, 20.07])) == "auto" and histogram_bins(np.array([3.0, 3.0])) == 1
