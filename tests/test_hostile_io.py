"""Off the happy path in and out: every bad file, path or format is refused with a message that
names it and the rule, a non-zero exit and no traceback; a failed write leaves nothing behind."""

import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import drydem as dd
from drydem.cli import main
from drydem.io.mesh import STL_TRIANGLE, read_mesh, write_mesh
from drydem.io.model_file import save_model
from drydem.io.target import load_target

#: a unit cube as OBJ statements, lines 1-14 (8 vertices, 6 faces)
CUBE = ("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
        "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n")


def fails(args: list[str], *messages: str):
    """Run drydem with ``args``: it must exit non-zero through click (SystemExit, no traceback)
    and say each of ``messages``."""
    result = CliRunner().invoke(main, [str(a) for a in args])
    assert result.exit_code != 0 and isinstance(result.exception, SystemExit), result.output
    assert "Traceback" not in result.output
    for message in messages:
        assert message in result.output
    return result


@pytest.mark.parametrize("name, text, message", [
    ("nan.obj", CUBE.replace("v 1 1 0\n", "v 1 nan 0\n"), "line 3: vertex 3: '1 nan 0': a vertex needs three finite numbers x y z"),
    ("inf.obj", CUBE.replace("v 1 1 0\n", "v 1 1 inf\n"), "line 3: vertex 3: '1 1 inf': a vertex needs three finite numbers"),
    ("short.obj", CUBE.replace("v 1 1 0\n", "v 1 1\n"), "line 3: vertex 3: '1 1': a vertex needs three finite numbers"),
    ("text.obj", CUBE.replace("v 1 1 0\n", "v 1 one 0\n"), "line 3: vertex 3: '1 one 0': the coordinates must be numbers"),
    ("underscore.obj", CUBE.replace("v 1 1 0\n", "v 1 1_0 0\n"), "line 3: vertex 3: '1 1_0 0': the coordinates must be numbers"),
    ("arabic.obj", CUBE.replace("v 1 1 0\n", "v 1 \u0661 0\n"), "line 3: vertex 3: '1 \u0661 0': the coordinates must be numbers"),
    ("missing.obj", CUBE.replace("f 5 6 7 8", "f 5 6 7 9"), "line 10: the face refers to vertex 9; the file has 8"),
    ("zero.obj", CUBE.replace("f 5 6 7 8", "f 0 6 7 8"), "line 10: the face refers to vertex 0, which does not exist"),
    ("back.obj", CUBE.replace("f 5 6 7 8", "f -9 6 7 8"), "line 10: the face refers to vertex -9, which does not exist"),
    ("two.obj", CUBE.replace("f 5 6 7 8", "f 5 6"), "line 10: a face needs at least 3 vertices, this one has 2"),
    ("word.obj", CUBE.replace("f 5 6 7 8", "f 5 six 7 8"), "line 10: 'six' is not a vertex number"),
    ("texture.obj", CUBE.replace("f 5 6 7 8", "f 5/abc/ 6 7 8"), "line 10: '5/abc/': the texture index 'abc' is not a whole number"),
    ("normal.obj", CUBE.replace("f 5 6 7 8", "f 5 6//n7 7 8"), "line 10: '6//n7': the normal index 'n7' is not a whole number"),
    ("slashes.obj", CUBE.replace("f 5 6 7 8", "f 5/1/1/1 6 7 8"), "line 10: '5/1/1/1': a face's vertex is v, v/vt, v/vt/vn or v//vn, not 4 numbers"),
    ("huge.obj", CUBE.replace("f 5 6 7 8", "f 5 6 7 " + "9" * 400),
     f"line 10: the face refers to vertex {'9' * 18}...{'9' * 18} (400 characters); the file has 8"),
    ("empty.obj", "", "empty.obj: no faces: the file holds no block"),
    ("points.obj", "# only vertices\nv 0 0 0\nv 1 0 0\n", "points.obj: no faces: the file holds no block"),
    ("open.obj", CUBE[:CUBE.rindex("f ")], "'part0' (from line 9) is not a closed surface"),
    ("half.obj", "o stone\nusemtl fixed\n" + CUBE.replace("f 3 4 8 7", "usemtl stone\nf 3 4 8 7"),
     "'stone': 4 of its 6 faces are marked fixed (from line 11), the others not"),
    ("cut.stl", "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n", "line 4: the file ends inside the solid 'a' (no endsolid)"),
    ("nameless.stl", "solid\n", "line 1: the file ends inside a nameless solid (no endsolid)"),  # found by a hunt: "the solid None"
    ("stray.stl", "solid a\nvertex 0 0 0\n", "line 2: 'vertex' is out of place (inside a solid)"),
    ("word.stl", "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 zero\n", "line 4: vertex: '0 0 zero': the coordinates must be numbers"),
    ("outside.stl", "solid a\nendsolid a\nfacet normal 0 0 1\n", "line 3: 'facet' is out of place (outside any solid)"),
    ("turned.obj", CUBE.replace("f 1 4 3 2", "f 1 2 3 4"),  # found by a hunt: OBJ and STL skipped the check VRML and compas make
     "the faces do not wind consistently: the edge [0.0, 0.0, 0.0] - [1.0, 0.0, 0.0] runs the same way in both its faces"),
    ("normal.stl", "solid a\nfacet normal nan 0.0 -1.0\n", "line 2: 'nan 0.0 -1.0': a facet normal needs three finite numbers x y z"),
    ("bare.stl", "solid a\nfacet\n", "line 2: 'facet': a facet begins 'facet normal nx ny nz'"),
    ("verb.stl", "solid a\nfacets\n", "line 2: 'facets' is not an ASCII STL statement"),
    ("edge.stl", "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid a\n",
     "line 7: the facet has 2 vertices; it needs 3 (an STL facet is a triangle)"),
    ("quad.stl", "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\n",
     "line 7: a fourth vertex in the facet of line 2: an STL facet is a triangle, 3 vertices"),
    ("other.stl", "solid a\nendsolid b\n", "line 2: endsolid names 'b', but it closes the solid 'a' of line 1: the name after "
     "endsolid, when given, must be the solid's"),
    ("cutname.stl", "solid a [fixed]\nendsolid a [", "line 2: endsolid names 'a [', but it closes the solid 'a [fixed]' of line 1"),
    ("empty.stl", "", "not an STL file: it does not start with 'solid' (ASCII), and its 0 bytes are too few for a binary STL "
     "(an 80-byte header and a 4-byte triangle count"),
    ("abc.stl", "abc", "not an STL file: it does not start with 'solid' (ASCII), and its 3 bytes are too few for a binary STL"),
    # found by a hunt: extra words and numbers were read past
    ("junk.obj", CUBE.replace("v 1 1 0\n", "v 1 1 0 abc\n"), "line 3: vertex 3: '1 1 0 abc': the coordinates must be numbers"),
    ("five.obj", CUBE.replace("v 1 1 0\n", "v 1 1 0 1 2\n"), "line 3: vertex 3: '1 1 0 1 2': 5 numbers; a vertex is x y z, x y z w or "
     "x y z r g b"),
    ("nanw.obj", CUBE.replace("v 1 1 0\n", "v 1 1 0 nan\n"), "line 3: vertex 3: '1 1 0 nan': a vertex needs three finite numbers"),
    ("four.stl", "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0 7\n", "line 4: vertex: '0 0 0 7': 4 numbers; a vertex is x y z"),
    ("loop.stl", "solid a\nfacet normal 0 0 1\nouter loop extra\n", "line 3: 'outer loop extra': the statement is outer loop, alone"),
    ("endloop.stl", "solid a\nfacet normal 0 0 1\nouter loop\nendloop x\n", "line 4: 'endloop x': the statement is endloop, alone"),
    ("nul.obj", "o b\x00c\n" + CUBE, "nul.obj: line 1: object name 'b\\x00c': must be a non-empty text on one line"),
    ("rtl.obj", "o a\u202eb\n" + CUBE, "rtl.obj: line 1: object name 'a\\u202eb': must be a non-empty text on one line"),
])
def test_a_bad_mesh_file_is_refused_naming_the_file_and_line(tmp_path, name, text, message):
    path = tmp_path / name
    path.write_text(text)
    fails(["check", path], f"{path}: ", message)


def test_a_huge_obj_vertex_number_is_shown_shortened(tmp_path):
    path = tmp_path / "huge.obj"
    path.write_text(CUBE.replace("f 5 6 7 8", "f 5 6 -" + "9" * 400 + " 8"))
    result = fails(["check", path], f"{path}: line 10: the face refers to vertex -{'9' * 17}...{'9' * 18} (401 characters), which does not exist")
    assert "9" * 40 not in result.output


def test_a_binary_stl_with_a_nan_names_the_triangle(tmp_path):
    records = np.zeros(2, dtype=STL_TRIANGLE)
    records["vertices"][1, 2, 0] = np.nan
    path = tmp_path / "nan.stl"
    path.write_bytes(bytes(80) + np.uint32(2).tobytes() + records.tobytes())
    fails(["check", path], f"{path}: binary triangle 1: a vertex is not a finite number (1 such triangles)")


def test_a_mesh_that_is_not_text_is_refused(tmp_path):
    path = tmp_path / "photo.obj"
    path.write_bytes(b"v 0 0 0\n\xff\xd8\xff\xe0")
    fails(["check", path], f"{path}: not a text file (byte 8 is not UTF-8)")


@pytest.mark.parametrize("name", ["walls", "walls.obj"])
def test_a_folder_as_target_is_called_a_folder(tmp_path, name):
    (tmp_path / name).mkdir()
    fails(["check", tmp_path / name], f"{tmp_path / name}: a folder, not a file, and not a built-in wall")


def test_obj_export_then_check_keeps_the_base_fixed_and_adds_no_second_one(tmp_path):
    path = tmp_path / "wall.obj"
    result = CliRunner().invoke(main, ["export", "WD3", str(path)])
    assert result.exit_code == 0 and "not the material, joint, contacts, supports or solver settings" in result.stderr
    result = CliRunner().invoke(main, ["check", str(path)])
    assert result.exit_code == 0 and "blocks          171 (170 movable, 1 fixed)" in result.output
    notes = [line for line in result.stderr.splitlines() if line.strip() and not line.startswith("compil")]
    assert notes == []  # no note (a cold cache says it compiles, its bar leaves a blank line)


def test_an_unnamed_mesh_prints_what_it_assumed(tmp_path):
    path = tmp_path / "cube.obj"
    path.write_text(CUBE)
    result = CliRunner().invoke(main, ["check", str(path)])
    assert result.exit_code == 0
    assert f"note: {path}: some faces are in no named object or solid: 1 block(s) are named part0" in result.stderr
    assert f"note: {path}: no block is marked fixed: the blocks stand on an added fixed block 'base'" in result.stderr


@pytest.mark.parametrize("output, message", [
    ("nowhere/wall.obj", "nowhere/wall.obj: the folder {tmp}/nowhere does not exist"),
    ("file.txt/wall.stl", "file.txt/wall.stl: {tmp}/file.txt is not a folder"),
    ("folder", "{tmp}/folder' is a directory"),
    ("wall.json/", "{tmp}/wall.json/' names a folder (it ends with a separator, . or ..); give a file name"),  # was written as wall.json
    ("wall.json/.", "{tmp}/wall.json/.' names a folder (it ends with a separator, . or ..)"),
])
def test_export_to_an_unwritable_path_names_it_and_writes_nothing(tmp_path, output, message):
    (tmp_path / "file.txt").write_text("keep")
    (tmp_path / "folder").mkdir()
    before = sorted(tmp_path.rglob("*"))
    fails(["export", "WD3", f"{tmp_path}/{output}"], message.format(tmp=tmp_path))
    assert sorted(tmp_path.rglob("*")) == before


def test_export_keeps_whatever_is_there_and_overwrites_only_a_regular_file(tmp_path):
    """An existing OUTPUT of any kind (a pipe, a broken link) is kept without --overwrite; with
    it, only a regular file is replaced (os.replace would put a file in a pipe's or link's
    place, not write through it); a name the system refuses is named."""
    import os

    os.mkfifo(tmp_path / "pipe.json")
    (tmp_path / "broken.json").symlink_to(tmp_path / "nowhere" / "x.json")
    for name in ("pipe.json", "broken.json"):
        fails(["export", "WD3", tmp_path / name], f"{name}: exists; pass --overwrite to replace it, or another OUTPUT")
        fails(["export", "WD3", tmp_path / name, "--overwrite"],
              f"{name}: exists and is not a regular file (a link, a pipe or a device): --overwrite replaces files only")
    assert (tmp_path / "broken.json").is_symlink() and not (tmp_path / "pipe.json").is_file() and not (tmp_path / "nowhere").exists()
    fails(["export", "WD3", tmp_path / ("a" * 300 + ".json")], "a.json: File name too long")


@pytest.mark.parametrize("target, message", [
    ("", "'': an empty TARGET; give a built-in wall (WD1"),
    ("pipe.toml", "pipe.toml: not a regular file, and not a built-in wall (WD1"),
    ("a" * 300 + ".toml", "a.toml: File name too long, and not a built-in wall"),
])
def test_a_target_that_is_no_file_is_named(tmp_path, monkeypatch, target, message):
    import os

    monkeypatch.chdir(tmp_path)
    os.mkfifo("pipe.toml")
    fails(["check", target], message)


def test_a_target_with_a_control_character_is_named_escaped():
    """Found by a hunt: a study's target "a\\u0000b.toml" was printed with its NUL byte raw."""
    with pytest.raises(dd.ModelError) as error:
        load_target("a\x00b\x1b[31m.toml")
    assert str(error.value).startswith("'a\\x00b\\x1b[31m.toml': no such file, and not a built-in wall")
    assert str(error.value).isprintable()


def test_a_failed_export_keeps_the_old_file_whole(tmp_path, monkeypatch):
    # the disk fills up half-way through writing: the old file stays, no partial file is left
    import errno

    import drydem.io.model_file

    def half_written(model, path):
        Path(path).write_text("[material]\ndensity = 18")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(drydem.io.model_file, "save_model", half_written)
    out = tmp_path / "wall.toml"
    out.write_text("the old file")
    fails(["export", "WD3", out, "--overwrite"], "wall.toml: cannot write: No space left on device")
    assert out.read_text() == "the old file" and [p.name for p in tmp_path.iterdir()] == ["wall.toml"]



def test_export_keeps_an_existing_file_unless_told_to_overwrite_it(tmp_path):
    out = tmp_path / "wall.toml"
    out.write_text("a model edited by hand")
    fails(["export", "WD3", out], "wall.toml: exists; pass --overwrite to replace it")
    assert out.read_text() == "a model edited by hand"
    result = CliRunner().invoke(main, ["export", "WD3", str(out), "--overwrite"])
    assert result.exit_code == 0 and out.read_text().startswith("[material]")

def test_a_name_a_mesh_cannot_keep_is_refused_before_writing(tmp_path):
    model = dd.build_model([dd.Block(name="base", shape=dd.box([0, 0, -1], [1, 1, 0]), fixed=True),
                            dd.Block(name=" padded", shape=dd.box([0, 0, 0], [1, 1, 1]))], density=1800.0)
    save_model(model, tmp_path / "padded.toml")
    out = tmp_path / "wall.obj"
    out.write_text("the old file")
    fails(["export", tmp_path / "padded.toml", out, "--overwrite"], "block ' padded': a mesh file cannot keep this name")
    assert out.read_text() == "the old file" and sorted(p.name for p in tmp_path.iterdir()) == ["padded.toml", "wall.obj"]


@pytest.mark.parametrize("output, message", [
    ("wall.webm", "wall.webm: cannot draw a figure in the format '.webm'; the suffix must be one of"),
    ("wall", "wall: cannot draw a figure in the format '(no suffix)'"),
    # matplotlib lists PGF, but writes it only through xelatex: a RuntimeError traceback without LaTeX
    ("wall.pgf", "wall.pgf: cannot draw a figure in the format '.pgf'; the suffix must be one of .eps, .gif"),
    ("nowhere/wall.png", "nowhere/wall.png: the folder {tmp}/nowhere does not exist"),
])
def test_show_to_a_bad_output_names_it_and_writes_nothing(tmp_path, output, message):
    fails(["show", "WD3", "-o", tmp_path / output], message.format(tmp=tmp_path))
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("output, message", [
    ("collapse.webm", "collapse.webm: cannot write '.webm' videos; the suffix must be .mp4 or .gif"),
    ("nowhere/collapse.gif", "nowhere/collapse.gif: the folder {tmp}/nowhere does not exist"),
])
def test_animate_refuses_a_bad_video_path_before_reading_any_frame(tmp_path, output, message):
    # the folder holds no series: an error about it would mean the frames were read first
    fails(["animate", tmp_path, "--out", tmp_path / output], message.format(tmp=tmp_path))


def test_limit_refuses_a_results_folder_it_cannot_make_before_the_analysis(tmp_path):
    (tmp_path / "file.txt").write_text("keep")
    result = fails(["limit", "WD3", "--out", tmp_path / "file.txt" / "results"],
                   f"{tmp_path / 'file.txt' / 'results'}: cannot write results there (Not a directory)")
    assert "finding the contacts" not in result.output


def test_limit_shows_each_stage_on_stderr(tmp_path):
    result = CliRunner().invoke(main, ["limit", "WD3", "--non-associative", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    # the kept stage lines "[time] stage"; the live bar's redraws end in carriage returns, not newlines
    lines = [line.rsplit("\r", 1)[-1] for line in result.stderr.split("\n")]
    stages = [re.sub(r"\d+(\.\d+)?", "N", line.split("] ", 1)[1]) for line in lines if line.startswith("[")]
    assert stages == ["finding the contacts of N blocks", "assembling the equilibrium matrix (N contact points)",
                      "solving the associative LP with HiGHS (interior point: N rows x N columns, N contact points)",
                      "non-associative iteration N of at most N: solving the LP with HiGHS (lambda N so far)"]


def test_ctrl_c_while_a_checkpoint_is_written_comes_after_it_is_whole(tmp_path, monkeypatch):
    # a SIGTERM that landed inside numpy's savez once ended a tilt with a ValueError from the
    # zip file's cleanup instead of the interrupt (tests/test_cli.py, SIGTERM while saving)
    import os
    import signal

    from drydem.engine import checkpoint

    real_savez = np.savez

    def interrupted_savez(file, **arrays):
        os.kill(os.getpid(), signal.SIGINT)  # delivered at once, were it not held
        real_savez(file, **arrays)

    monkeypatch.setattr(checkpoint.np, "savez", interrupted_savez)
    sim = dd.Simulation(dd.build_model([dd.Block(name="base", shape=dd.box([0, 0, -1], [1, 1, 0]), fixed=True),
                                        dd.Block(name="brick", shape=dd.box([0, 0, 0], [1, 1, 1]))], density=1800.0))
    path = tmp_path / "checkpoint.npz"
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)  # Ctrl-C's own, whatever a test before set
    try:
        with pytest.raises(KeyboardInterrupt):
            checkpoint.save_checkpoint(path, sim.snapshot(), {"theta_deg": 1.5})
    finally:
        signal.signal(signal.SIGINT, previous)
    snapshot, progress = checkpoint.load_checkpoint(path)
    assert float(progress["theta_deg"]) == 1.5 and np.array_equal(snapshot.state.position, sim.state.position)
    assert [p.name for p in tmp_path.iterdir()] == ["checkpoint.npz"]


def test_a_mesh_file_s_byte_order_mark_is_dropped_and_a_statement_not_obj_is_named(tmp_path):
    """Found by a hunt: a UTF-8 byte order mark was read as part of the first statement (an
    OBJ lost its object's name, or its first vertex; an STL was no STL), and a statement that is
    not OBJ (a typo, V for v) was skipped without a word. An OBJ vertex may give w or a colour."""
    obj, stl = tmp_path / "bom.obj", tmp_path / "bom.stl"
    obj.write_bytes(b"\xef\xbb\xbf" + ("o brick\n" + CUBE.replace("v 1 1 1", "v 1 1 1 0.5 0.5 0.5") + "V 1 1 1\nvt 0 0\n").encode())
    blocks, notes = read_mesh(obj)
    assert [b.name for b in blocks] == ["brick"]
    assert notes == [f"{obj}: not OBJ statements, skipped: 'V' (line 16)"]
    write_mesh(dd.build_model(blocks, density=1800.0), stl)
    stl.write_bytes(b"\xef\xbb\xbf" + stl.read_bytes())
    assert [b.name for b in read_mesh(stl)[0]] == ["brick"]
