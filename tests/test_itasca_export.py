"""`drydem export TARGET model.dat`: an Itasca 3DEC command file (drydem.io.itasca) whose every
statement is a documented 3DEC command and which builds the model's blocks, supports, joints,
densities, damping and gravity, read back by an independent reader (tests/oracles/threedec.py)."""

import math
import re

import numpy as np
import pytest
from click.testing import CliRunner

import drydem as dd
from drydem.cli import main
from drydem.io.itasca import threedec_commands, write_3dec
from drydem.io.model_file import save_model
from drydem.io.target import load_target
from oracles.threedec import read_deck, signed_volume, statements

#: the Itasca manual (docs.itascacg.com): 3DEC 9.0 block commands, 3DEC 7.0 modelling guide, and
#: the model commands common to Itasca's codes; each statement form below follows its page
BLOCK = "itasca900/3dec/block/doc/manual/block_manual/block_commands/block/cmd_block.{}.html"
CONTACT = "itasca900/3dec/block/doc/manual/block_manual/block_commands/block.contact/cmd_block.contact.{}.html"
MODEL = "itasca900/common/kernel/doc/manual/model/commands/cmd_model.{}.html"
SINGLE_BLOCKS = "3dec700/3dec/docproject/source/modeling/problemsolving/singleblocks.html"
MOHR = "itasca900/3dec/docproject/source/theory/mohrcoulomb/mohrcoulomb.html"

NUMBER = r"-?\d+(\.\d+)?(e[-+]?\d+)?"
VERTEX = rf"{NUMBER},{NUMBER},{NUMBER}"
NAME = r"'[^'=\n]+'"
RANGE = rf"range group {NAME} slot {NAME}"
JOINT = rf"stiffness-normal {NUMBER} stiffness-shear {NUMBER} friction {NUMBER} cohesion {NUMBER} tension {NUMBER}"
#: (statement form, manual page): the commands, keywords and argument forms as documented
DOCUMENTED = [
    (r"model new", MODEL.format("new")),
    (r"model large-strain on", MODEL.format("large-strain")),
    (rf"model gravity {NUMBER} {NUMBER} {NUMBER}", MODEL.format("gravity")),
    (rf"block create group {NAME} slot {NAME} polyhedron( face {VERTEX} {VERTEX} {VERTEX}( {VERTEX})*){{4,}}",
     f"{BLOCK.format('create')}; {SINGLE_BLOCKS}"),
    (rf"block group {NAME} slot {NAME}( {RANGE})?", BLOCK.format("group")),
    (rf"block fix( (velocity|rotation)-[xyz])? {RANGE}", BLOCK.format("fix")),
    (rf"block property density {NUMBER}( {RANGE})?", BLOCK.format("property")),
    (r"block mechanical damping local " + NUMBER, BLOCK.format("mechanical")),
    (r"block contact generate-subcontacts", CONTACT.format("generate-subcontacts")),
    (r"block contact jmodel assign mohr", CONTACT.format("jmodel")),
    (rf"block contact property {JOINT}", f"{CONTACT.format('property')}; {MOHR}"),
    (rf"block contact material-table default property {JOINT}", CONTACT.format("material-table")),
]


def held_and_heavy_model() -> dd.Model:
    """Three blocks on a fixed base: one heavier than the others, x translations and z rotations
    held by [supports], a joint with cohesion and tension."""
    blocks = [dd.Block(name="base", shape=dd.box([-0.1, -0.1, -0.05], [0.5, 0.1, 0.0]), fixed=True)]
    blocks += [dd.Block(name=f"b{k}", shape=dd.box([0.1 * k, -0.05, 0.0], [0.1 * k + 0.1, 0.05, 0.08]),
                        density=2400.0 if k == 1 else None) for k in range(3)]
    return dd.build_model(blocks, density=1800.0, supports=dd.Supports(fix_x=True, fix_rz=True),
                          joint=dd.JointMaterial(kn=2e8, ks=1e8, friction=0.7, cohesion=1e3, tension=500.0))


MODELS = {"WD3": lambda: load_target("WD3").model, "building-small": lambda: load_target("building-small").model,
          "held and heavy": held_and_heavy_model}


@pytest.fixture(scope="module", params=list(MODELS))
def exported(request):
    """(model, command file text) of each model."""
    model = MODELS[request.param]()
    return model, threedec_commands(model)


def test_every_line_is_a_comment_a_blank_or_a_documented_3dec_command(exported):
    _, text = exported
    for number, command in statements(text):
        forms = [page for form, page in DOCUMENTED if re.fullmatch(form, command)]
        assert forms, f"line {number}: {command[:120]!r} is no documented 3DEC command form"
    for number, line in enumerate(text.splitlines(), start=1):
        # the manual: a line may be continued, "but do not continue a line from within a vector"
        assert not re.search(r",\s*\.\.\.$|^\s*,", line), f"line {number} breaks a vertex"


def test_a_block_fix_always_has_a_range_as_one_without_fixes_every_block(exported):
    # cmd_block.fix: "If no range is specified, all visible blocks are fixed"
    _, text = exported
    assert all(" range " in command for _, command in statements(text) if command.startswith("block fix"))


def test_the_blocks_read_back_are_the_models_with_faces_clockwise_from_outside(exported):
    model, text = exported
    deck = read_deck(text)
    assert list(deck.faces) == list(model.block_name)
    for name, shape in zip(model.block_name, model.block_shape):
        faces = deck.faces[name]
        written = np.concatenate(faces)
        gap = np.linalg.norm(written[:, None, :] - shape.vertices[None, :, :], axis=2)
        assert gap.min(axis=1).max() <= 1e-9 * shape.size, name  # every written vertex is a vertex of the block
        assert (gap.min(axis=0) <= 1e-9 * shape.size).all(), name  # and every vertex of the block is written
        assert len(faces) == len(shape.faces)
        # 3DEC (singleblocks.html): vertices "in clockwise order, looking at the face from outside", so
        # the divergence theorem over the faces as written gives minus the block's volume
        assert signed_volume(faces) == pytest.approx(-shape.volume, rel=1e-12), name


def test_the_fixed_degrees_of_freedom_read_back_are_the_models(exported):
    model, text = exported
    deck = read_deck(text)
    held = np.array([deck.held[name] for name in model.block_name])
    assert (held == model.block_fixed).all()
    fixed = {name for name, row in zip(model.block_name, model.block_fixed) if row.all()}
    assert {name for name, row in deck.held.items() if all(row)} == fixed and fixed


def test_joint_density_damping_and_gravity_read_back_are_the_models(exported):
    model, text = exported
    deck = read_deck(text)
    joint = model.joint
    assert deck.jmodel == "mohr"
    assert deck.contact["stiffness-normal"] == joint.kn and deck.contact["stiffness-shear"] == joint.ks
    # 3DEC's friction is an angle in degrees (mohrcoulomb.html), drydem's a coefficient mu = tan(phi)
    assert math.tan(math.radians(deck.contact["friction"])) == pytest.approx(joint.friction, rel=1e-14)
    assert deck.contact["cohesion"] == joint.cohesion and deck.contact["tension"] == joint.tension
    assert deck.default_contact == deck.contact
    assert [deck.density[name] for name in model.block_name] == model.block_density.tolist()
    assert deck.damping == model.solver.damping
    assert deck.gravity == (0.0, 0.0, -dd.G)


def test_the_documented_forms_are_those_the_writer_uses():
    # the table above holds no form that no export needs: the held and heavy model uses each one
    text = threedec_commands(held_and_heavy_model())
    used = [form for form, _ in DOCUMENTED if any(re.fullmatch(form, command) for _, command in statements(text))]
    assert used == [form for form, _ in DOCUMENTED]
    assert "block fix velocity-x range group 'held-x-rz' slot 'support'" in text
    assert "block property density 2400.0 range group 'b1' slot 'drydem'" in text


def test_the_in_plane_walls_hold_y_and_the_rotations_out_of_plane():
    # WD3 is in plane (drydem.model.assembly.Model.in_plane): fix_y, and rx, rz held by symmetry
    text = threedec_commands(load_target("WD3").model)
    assert [line for line in text.splitlines() if line.startswith("block fix")] == [
        "block fix range group 'fixed' slot 'support'",
        "block fix velocity-y range group 'held-y-rx-rz' slot 'support'",
        "block fix rotation-x range group 'held-y-rx-rz' slot 'support'",
        "block fix rotation-z range group 'held-y-rx-rz' slot 'support'",
    ]


def test_the_header_names_drydem_the_model_and_si_units():
    model = held_and_heavy_model()
    lines = threedec_commands(model).splitlines()
    assert lines[0].startswith(f"; drydem {dd.__version__}: Itasca 3DEC command file")
    assert lines[1] == f"; model: {model.source}" and lines[2].startswith("; units SI: m, kg, s")


@pytest.mark.parametrize("name", ["wd3.dat", "wd3.3ddat"])
def test_drydem_export_writes_a_3dec_file(tmp_path, name):
    out = tmp_path / name
    result = CliRunner().invoke(main, ["export", "WD3", str(out)])
    assert result.exit_code == 0, result.output
    assert "WD3: 171 blocks -> " in result.output
    assert out.read_text() == threedec_commands(load_target("WD3").model)
    assert [p.name for p in tmp_path.iterdir()] == [name]


def test_an_existing_3dec_file_is_replaced_only_with_overwrite(tmp_path):
    out = tmp_path / "old.dat"
    out.write_text("the old file")
    result = CliRunner().invoke(main, ["export", "WD3", str(out)])
    assert result.exit_code == 1 and "exists; pass --overwrite" in result.output and out.read_text() == "the old file"
    result = CliRunner().invoke(main, ["export", "WD3", str(out), "--overwrite"])
    assert result.exit_code == 0 and out.read_text() == threedec_commands(load_target("WD3").model)


def test_an_unknown_suffix_names_the_3dec_ones(tmp_path):
    result = CliRunner().invoke(main, ["export", "WD3", str(tmp_path / "wd3.3dec")])
    assert result.exit_code == 1 and "unknown output type '.3dec'" in result.output
    assert ".dat, .3ddat" in result.output and "Traceback" not in result.output


@pytest.mark.parametrize("change, message", [
    ({"joint": dd.JointMaterial(model="power", kn_exponent=0.5, stress_ref=1e3, kn_min=1e6)},
     "[joint] model = 'power': 3DEC's Mohr-Coulomb joint (jmodel mohr) has constant stiffness"),
    ({"name": "it's"}, "block \"it's\": a 3DEC group name cannot keep this name"),
    ({"name": "slot=name"}, "block 'slot=name': a 3DEC group name cannot keep this name"),
])
def test_what_3dec_cannot_take_is_refused_before_writing(tmp_path, change, message):
    blocks = [dd.Block(name="base", shape=dd.box([0, 0, -1], [1, 1, 0]), fixed=True),
              dd.Block(name=change.get("name", "brick"), shape=dd.box([0, 0, 0], [1, 1, 1]))]
    model = dd.build_model(blocks, density=1800.0, **{k: v for k, v in change.items() if k == "joint"})
    with pytest.raises(dd.ModelError, match=re.escape(message)):
        write_3dec(model, tmp_path / "direct.dat")
    save_model(model, tmp_path / "model.toml")
    out = tmp_path / "model.dat"
    out.write_text("the old file")
    result = CliRunner().invoke(main, ["export", str(tmp_path / "model.toml"), str(out), "--overwrite"])
    assert result.exit_code == 1 and message in result.output and "Traceback" not in result.output
    assert out.read_text() == "the old file"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.dat", "model.toml"]


@pytest.mark.parametrize("call, words", [
    (lambda path: write_3dec(None, path), "write_3dec model = None: must be a Model"),
    (lambda path: write_3dec(load_target("WD3").model, None), "write_3dec path = None: must be a file path"),
    (lambda path: threedec_commands("WD3"), "threedec_commands model = 'WD3': must be a Model"),
])
def test_an_argument_that_is_no_model_or_path_is_named(tmp_path, call, words):
    """Found by a hunt: a bare TypeError (path None) and AttributeError (model None) from inside."""
    with pytest.raises(dd.ModelError, match=re.escape(words)):
        call(tmp_path / "x.dat")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("solver, criterion", [
    (dd.SolverSettings(ratio=1e-6), "ratio: the largest unbalanced force over the mean block weight below 1e-06"),
    (dd.SolverSettings(criterion="velocity", max_velocity=1e-9), "velocity: the largest block point speed below 1e-09 m/s"),
])
def test_the_closing_comment_gives_the_models_own_criterion(solver, criterion):
    # found by a hunt: it always said ratio-local 1e-5, whatever the model's [solver] said
    model = held_and_heavy_model().replace(solver=solver)
    last = threedec_commands(model).splitlines()[-1]
    assert f"the convergence criterion ({criterion})" in last
    assert f"model solve ratio-local {solver.ratio!r}" in last
