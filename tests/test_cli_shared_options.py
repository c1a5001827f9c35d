"""Every command that reads data takes the same options: one name, one meaning, one help text, from one
definition (``ftcal/cli/_data_options.py``); old spellings still work, hidden from ``--help``."""

from __future__ import annotations

import argparse

import pytest

from ftcal.cli import build_parser, main

#: The commands and the options each must take, by what it reads.
DATASET = ("--channels", "--wrench", "--axes", "--groups", "--force-unit", "--torque-unit", "--exclude-saturated")
READS = {
    "fit": DATASET + ("--cv", "--alpha", "--seed"),
    "evaluate": DATASET + ("--alpha",),
    "report": DATASET + ("--cv", "--seed"),
    "tune": DATASET + ("--cv", "--folds", "--alpha", "--seed"),
    "benchmark dataset": DATASET + ("--cv", "--folds", "--alpha", "--seed"),
    "plan": DATASET + ("--seed",),  # plan --next reads a dataset
    "predict": ("--channels",),
    "retare": ("--channels", "--force-unit", "--torque-unit"),
    "identify-load": ("--force-unit", "--torque-unit", "--cv", "--tf"),
    "compensate": ("--force-unit", "--torque-unit", "--tf"),
}
#: Options whose meaning must not change from one command to the next.
SHARED = sorted({o for options in READS.values() for o in options})


def _commands(parser, prefix=""):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                nested = any(isinstance(a, argparse._SubParsersAction) for a in sub._actions)
                yield from _commands(sub, f"{prefix}{name} ") if nested else [(prefix + name, sub)]


COMMANDS = dict(_commands(build_parser()))


def _visible(sub, option):
    return next((a for a in sub._actions if option in a.option_strings and a.help != argparse.SUPPRESS), None)


def _meaning(action):
    kind = getattr(action.type, "__qualname__", repr(action.type))  # the parser function, not one closure
    return (type(action).__name__, action.dest, kind, action.metavar, action.choices, action.nargs, action.help)


def test_the_table_names_real_commands():
    assert set(READS) <= set(COMMANDS), set(READS) - set(COMMANDS)


@pytest.mark.parametrize("option", SHARED)
def test_a_shared_option_has_one_name_meaning_and_help_text_on_every_command(option):
    meanings = {name: _meaning(a) for name, sub in COMMANDS.items() if (a := _visible(sub, option)) is not None}
    for name, options in READS.items():
        if option in options:
            assert name in meanings, f"{name} does not take {option}"
    assert len(set(meanings.values())) == 1, {name: m[1:] for name, m in meanings.items()}


@pytest.mark.parametrize("argv, old", [
    (["tune", "d.csv", "--model", "linear"], ["--group-folds"]),
    (["tune", "d.csv", "--model", "linear"], ["--random-folds"]),
    (["benchmark", "dataset", "d.csv"], ["--random-folds"]),
    (["identify-load", "poses.csv"], ["--drift-cv", "7"]),
    (["prepare", "logs"], ["--channels", "8"]),
])
def test_removed_old_spellings_are_refused_in_one_line(argv, old, tmp_path, monkeypatch, capsys):
    # 0.1.0 is unreleased: the old spellings (--group-folds, --drift-cv, prepare --channels N) are gone
    monkeypatch.chdir(tmp_path)
    for name in ("d.csv", "poses.csv"):
        (tmp_path / name).write_text("x\n")  # inputs are checked for existence at parse time
    (tmp_path / "logs").mkdir()
    from ftcal.cli import main

    code = main(argv + old)
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and old[0] in err[0] and err[0].startswith("ftcal: error: ")
    assert f"{old[0]} is now --" in err[0]  # what to write instead


@pytest.mark.parametrize("argv", [["fit", "d.csv"], ["tune", "d.csv"], ["identify-load", "d.csv"]])
def test_every_name_option_takes_a_file_stem_only(tmp_path, capsys, argv):
    # identify-load took any --name: '../x' wrote the tool file outside --out
    (tmp_path / "d.csv").write_text("s0\n1\n")
    argv = [str(tmp_path / a) if a == "d.csv" else a for a in argv]
    assert main(argv + ["--name", "../x", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "argument --name: '../x': use letters, digits, '-' and '_' only" in err, err
    assert not (tmp_path / "o").exists() and not (tmp_path / "x.tool.json").exists()
