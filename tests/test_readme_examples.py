"""Every example of the README runs: each TOML file loads as what it is, the Python runs, and
every ``drydem`` command line names a command and options that exist.

The blocks are found by parsing the README's fences, so an example added anywhere is tested;
a fenced block of another language, or a TOML file of no known kind, fails here until this
module is taught to run it.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest
from click.testing import CliRunner

from drydem.parametric.study import load_study
from drydem.cli import main
from drydem.io.target import load_target
from drydem.masonry.walls import is_wall_file

README = Path(__file__).resolve().parents[1] / "README.md"
#: the fence languages this module runs
TESTED = ("toml", "python", "bash")
#: shell operators that end a command
SEPARATORS = {"&&", "||", ";", "|", "&"}


def fenced_blocks(markdown: str) -> list[tuple[int, str, str]]:
    """The fenced code blocks of ``markdown`` as (line of the opening fence, language, code).
    As CommonMark has it: a fence is a line of three or more backticks or tildes indented by
    at most three spaces, the first word after an opening one is the language, and a closing
    one is of the same character, at least as long, with nothing after it."""
    fence = re.compile(r" {0,3}(`{3,}|~{3,})[ \t]*(.*)")
    blocks, opening, lines = [], None, []
    for number, line in enumerate(markdown.splitlines(), start=1):
        match = fence.fullmatch(line)
        if opening is None:
            if match:
                opening, start, language, lines = match[1], number, (match[2].split() or [""])[0].lower(), []
        elif match and match[1][0] == opening[0] and len(match[1]) >= len(opening) and not match[2].strip():
            blocks.append((start, language, "\n".join(lines) + "\n"))
            opening = None
        else:
            lines.append(line)
    assert opening is None, f"README.md, line {start}: the code block is never closed"
    return blocks


BLOCKS = fenced_blocks(README.read_text(encoding="utf-8"))


def examples(language: str) -> list:
    return [pytest.param(line, code, id=f"line{line}") for line, lang, code in BLOCKS if lang == language]


def drydem_commands(script: str) -> list[list[str]]:
    """The arguments after ``drydem`` of every ``drydem ...`` command of a shell script."""
    commands = []
    for line in script.replace("\\\n", " ").splitlines():
        lexer = shlex.shlex(line, posix=True, punctuation_chars=True)
        lexer.whitespace_split = True
        command: list[str] = []
        for word in [*lexer, ";"]:
            if word not in SEPARATORS:
                command.append(word)
                continue
            if command[:1] == ["drydem"]:
                commands.append(command[1:])
            command = []
    return commands


def passes_drydem_check(path: Path) -> None:
    """``drydem check`` (what the README says validates a model) builds it, its contacts and timestep."""
    result = CliRunner().invoke(main, ["check", str(path)])
    assert result.exit_code == 0, result.output


def is_a_buildable_wall(path: Path) -> None:
    """A wall file passes ``drydem check`` and has no brick drawn over nothing."""
    passes_drydem_check(path)
    assert load_target(str(path)).wall.layout.unsupported() == []


def is_a_study_of_existing_targets(path: Path) -> None:
    """A study loads with its runs (``drydem sweep`` would run them: too slow here) and names
    targets that resolve."""
    study = load_study(path)
    assert study.runs
    for target in {run.target for run in study.runs}:
        load_target(target)


#: each kind of TOML file: (name, how to recognise its tables, the check); the first match wins
TOML_KINDS = [
    ("model file", lambda data: "block" in data, passes_drydem_check),
    ("wall file", is_wall_file, is_a_buildable_wall),
    ("study", lambda data: "study" in data or "grid" in data, is_a_study_of_existing_targets),
]


def test_every_readme_code_block_is_of_a_language_this_module_runs():
    untested = [f"line {line}: {language or '(none)'}" for line, language, _ in BLOCKS if language not in TESTED]
    assert not untested, f"README code blocks that no test runs (tested: {TESTED}): {untested}"


def test_the_readme_has_examples_of_every_kind():
    # a parser that found nothing would pass every parametrised test below
    languages = [language for _, language, _ in BLOCKS]
    assert all(languages.count(language) for language in TESTED)


@pytest.mark.parametrize("line, code", examples("toml"))
def test_readme_toml_example_loads_as_the_file_it_is(line, code, tmp_path):
    import tomllib

    data = tomllib.loads(code)
    kinds = [(name, check) for name, recognise, check in TOML_KINDS if recognise(data)]
    assert kinds, (f"README.md, line {line}: a TOML example of no known kind (tables {sorted(data)}); "
                   f"known: {[name for name, _, _ in TOML_KINDS]}")
    path = tmp_path / "example.toml"
    path.write_text(code, encoding="utf-8")
    _, check = kinds[0]
    check(path)


@pytest.mark.slow
@pytest.mark.parametrize("line, code", examples("python"))
def test_readme_python_example_runs(line, code, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # whatever it writes stays out of the repository
    exec(compile(code, f"README.md, line {line}", "exec"), {"__name__": "readme_example"})


@pytest.mark.parametrize("arguments", [
    pytest.param(arguments, id=" ".join(["drydem", *arguments]))
    for _, language, code in BLOCKS if language == "bash" for arguments in drydem_commands(code)
])
def test_readme_drydem_command_names_a_command_and_options_that_exist(arguments):
    # --help stops before any file is read, after click has refused unknown options
    assert arguments and arguments[0] in main.commands, f"no command 'drydem {' '.join(arguments)}'"
    result = CliRunner().invoke(main, [*arguments, "--help"])
    assert result.exit_code == 0, result.output


def test_drydem_commands_are_found_in_shell_lines():
    script = "pip install -e . && drydem tilt WD3 --adaptive # a comment\ndrydem check \\\n  wall.toml; ls | drydem designs\n"
    assert drydem_commands(script) == [["tilt", "WD3", "--adaptive"], ["check", "wall.toml"], ["designs"]]


def test_fenced_blocks_are_read_as_commonmark_has_them():
    markdown = "text\n```toml\na = 1\n```\n~~~~ Python extra\n```\nx = 1\n~~~~\n  ```\nplain\n  ```\n"
    assert fenced_blocks(markdown) == [(2, "toml", "a = 1\n"), (5, "python", "```\nx = 1\n"), (9, "", "plain\n")]
