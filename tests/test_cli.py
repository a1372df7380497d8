"""The command line: drydem check."""

from click.testing import CliRunner

from drydem.cli import main


def test_check_prints_blocks_contacts_mass_and_timestep():
    result = CliRunner().invoke(main, ["check", "perforated_wall"])
    assert result.exit_code == 0, result.output
    for expected in ["blocks          174 (173 movable, 1 fixed)", "sub-contacts", "mass            0.42768 kg", "timestep"]:
        assert expected in result.output


def test_check_settle_converges_and_reports_the_settlement():
    result = CliRunner().invoke(main, ["check", "perforated_wall", "--settle"])
    assert result.exit_code == 0, result.output
    assert "equilibrium     converged" in result.output and "settlement" in result.output


def test_bad_model_exits_with_its_message(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("[joint]\nkn = -1.0\n[[block]]\nbox = { min = [0, 0, 0], max = [1, 1, 1] }\n")
    result = CliRunner().invoke(main, ["check", str(path)])
    assert result.exit_code == 1
    assert "broken.toml: [joint] kn = -1.0: must be a positive number" in result.output
